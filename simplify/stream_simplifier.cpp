#include "simplify/stream_simplifier.h"

#include <algorithm>
#include <atomic>
#include <cstring>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "mesh/fresh_memory.h"
#include "mesh/index.h"

namespace gtn {

StreamSimplifier::StreamSimplifier(const MergeTree& tree, uint64_t n, MeshSink& out)
    : tree_(tree), n_(std::min<uint64_t>(n, tree.merges)), out_(out) {}

Status StreamSimplifier::beginLevel(const LevelHeader& header) {
  GTN_RETURN_IF_ERROR(prepare(header));
  return out_.beginLevel(out_header_);
}

Status StreamSimplifier::prepare(const LevelHeader& header) {
  if (header.points != tree_.points())
    return invalidData("simplification: the level has " + std::to_string(header.points) + " vertices, its merge tree " +
                       std::to_string(tree_.points()));
  if (!tree_.checked) GTN_RETURN_IF_ERROR(tree_.check("simplification: merge tree"));
  in_header_ = header;
  cell_bytes_ = 0;
  for (const FieldDesc& d : header.cell_fields) cell_bytes_ += d.itemBytes();
  const size_t np = tree_.points();
  const size_t survivors = np - n_;
  // Ancestors after the first n_ merges (computeAncestors, fused with the counts the merges remove):
  // order[r - 1] = the vertex of rank r <= n_, order[n_] collects the others.
  std::vector<uint32_t> order(n_ + 1);
  out_of_.resize(np);
  uint64_t removed = 0, boundary_removed = 0;
  for (size_t v = 0; v < np; ++v) {
    out_of_[v] = static_cast<uint32_t>(v);
    const uint32_t r = tree_.rank[v] - 1;  // roots (rank 0) wrap around to the largest value
    const bool applied = r < n_;
    order[applied ? r : n_] = static_cast<uint32_t>(v);
    removed += applied ? tree_.removed[v] : 0;
    boundary_removed += applied ? 2 * tree_.boundary[v] : 0;
  }
  for (uint64_t r = n_; r-- > 0;) out_of_[order[r]] = out_of_[tree_.parent[order[r]]];
  // A survivor's entry becomes its output id, then every other entry the output id of its ancestor
  // (a survivor, whose entry is final by then).
  survives_.assign(np, 0);
  uint32_t next = 0;
  for (size_t v = 0; v < np; ++v) {
    if (out_of_[v] == v) {
      survives_[v] = 1;
      out_of_[v] = next++;
    }
  }
  if (next != survivors) return invalidData("simplification: the merge tree's merge count disagrees with its vertices");
  refs_.assign(survivors, 0);
  for (size_t v = 0; v < np; ++v) {
    if (!survives_[v]) out_of_[v] = out_of_[out_of_[v]];
    ++refs_[out_of_[v]];
  }
  received_ = emitted_ = 0;
  out_tets_ = out_triangles_ = dropped_tets_ = 0;
  held_.clear();
  held_values_.clear();
  free_slots_.clear();
  wait_head_.assign(survivors, kNoIndex);
  wait_tail_.assign(survivors, kNoIndex);
  held_count_ = peak_held_ = 0;
  in_boundary_ = true;
  out_header_ = header;
  out_header_.merges = header.merges + n_;
  out_header_.points = header.points - n_;
  if (removed > header.tets || boundary_removed > header.boundary_triangles)
    return invalidData("simplification: the merge tree removes more elements than the level has");
  out_header_.tets = header.tets - removed;
  out_header_.boundary_triangles = header.boundary_triangles - boundary_removed;
  return Status::ok();
}

namespace {
// The items i < n for which keep(i) holds, in order, written by put(i, place) at places 0, 1, ...
// counted in blocks on every thread; returns how many.
template <class Keep, class Put>
size_t compactInOrder(size_t n, const Keep& keep, const Put& put) {
  constexpr size_t kBlock = size_t{1} << 14;
  const size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<size_t> first(blocks + 1, 0);
  tbb::parallel_for(size_t{0}, blocks, [&](size_t b) {
    size_t k = 0;
    for (size_t i = b * kBlock, end = std::min(n, i + kBlock); i < end; ++i) k += keep(i);
    first[b + 1] = k;
  });
  for (size_t b = 0; b < blocks; ++b) first[b + 1] += first[b];
  tbb::parallel_for(size_t{0}, blocks, [&](size_t b) {
    size_t at = first[b];
    for (size_t i = b * kBlock, end = std::min(n, i + kBlock); i < end; ++i)
      if (keep(i)) put(i, at++);
  });
  return first[blocks];
}
}  // namespace

Status StreamSimplifier::wholeLevel(const LevelHeader& header, TetMesh&& mesh,
                                    std::vector<std::array<uint32_t, 3>>&& boundary) {
  GTN_RETURN_IF_ERROR(prepare(header));
  const size_t np = mesh.numPoints();
  if (np != header.points || mesh.numTets() != header.tets || boundary.size() != header.boundary_triangles ||
      mesh.coords.size() != 3 * np)
    return invalidData("simplification: the level given whole disagrees with its header");
  for (const auto& f : boundary)
    if (std::max({f[0], f[1], f[2]}) >= np)
      return invalidData("simplification: a boundary triangle refers to a vertex beyond the level");
  const size_t survivors = out_header_.points;
  TetMesh out;
  out.coord_type = mesh.coord_type;
  out.metadata = mesh.metadata;
  resizePopulated(out.coords, 3 * survivors);
  for (const Field& f : mesh.point_fields) {
    out.point_fields.emplace_back(f.name, f.components, f.type, 0);
    resizePopulated(out.point_fields.back().bytes, survivors * f.components * f.valueSize());
  }
  // Survivors keep their order: vertex v's place is out_of_[v].
  tbb::parallel_for(tbb::blocked_range<size_t>(0, np, size_t{1} << 14), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t v = r.begin(); v < r.end(); ++v) {
      if (!survives_[v]) continue;
      const uint32_t o = out_of_[v];
      std::copy_n(mesh.coords.data() + 3 * v, 3, out.coords.data() + 3 * size_t{o});
      for (size_t i = 0; i < mesh.point_fields.size(); ++i) out.point_fields[i].copyItem(mesh.point_fields[i], v, o);
    }
  });
  auto mapped = [&](const Tet& t) { return Tet{out_of_[t[0]], out_of_[t[1]], out_of_[t[2]], out_of_[t[3]]}; };
  auto distinct = [](const Tet& q) {
    return q[0] != q[1] && q[0] != q[2] && q[0] != q[3] && q[1] != q[2] && q[1] != q[3] && q[2] != q[3];
  };
  const size_t nt = mesh.numTets();
  resizePopulated(out.tets, out_header_.tets);
  std::vector<uint32_t> kept_cell;  // per output tetrahedron, its input one (for the cell fields)
  if (!mesh.cell_fields.empty()) resizePopulated(kept_cell, out_header_.tets);
  std::atomic<bool> overflow{false}, beyond{false};
  const size_t tets = compactInOrder(
      nt,
      [&](size_t t) {
        const Tet& q = mesh.tets[t];
        if (std::max({q[0], q[1], q[2], q[3]}) >= np) {
          beyond.store(true, std::memory_order_relaxed);
          return false;
        }
        return distinct(mapped(q));
      },
      [&](size_t t, size_t at) {
        if (at >= out.tets.size()) {
          overflow.store(true, std::memory_order_relaxed);
          return;
        }
        out.tets[at] = mapped(mesh.tets[t]);
        if (!kept_cell.empty()) kept_cell[at] = static_cast<uint32_t>(t);
      });
  if (beyond.load()) return invalidData("simplification: a tetrahedron refers to a vertex beyond the level");
  dropped_tets_ = nt - tets;
  if (overflow.load() || tets != out_header_.tets)
    return invalidData("simplification: " + std::to_string(tets) + " tetrahedra, the merge tree implies " +
                       std::to_string(out_header_.tets));
  for (const Field& f : mesh.cell_fields) {
    out.cell_fields.emplace_back(f.name, f.components, f.type, 0);
    Field& g = out.cell_fields.back();
    resizePopulated(g.bytes, tets * f.components * f.valueSize());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, tets, size_t{1} << 14), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i) g.copyItem(f, kept_cell[i], i);
    });
  }
  std::vector<std::array<uint32_t, 3>> out_boundary;
  out_boundary.reserve(out_header_.boundary_triangles);
  for (const auto& f : boundary) {
    const std::array<uint32_t, 3> o = {out_of_[f[0]], out_of_[f[1]], out_of_[f[2]]};
    if (o[0] != o[1] && o[0] != o[2] && o[1] != o[2]) out_boundary.push_back(o);
  }
  if (out_boundary.size() != out_header_.boundary_triangles)
    return invalidData("simplification: " + std::to_string(out_boundary.size()) +
                       " boundary triangles, the merge tree implies " + std::to_string(out_header_.boundary_triangles));
  received_ = emitted_ = static_cast<uint32_t>(np);
  out_tets_ = tets;
  out_triangles_ = out_boundary.size();
  mesh = TetMesh();  // the input's memory back before the output's consumer runs
  return out_.wholeLevel(out_header_, std::move(out), std::move(out_boundary));
}

Status StreamSimplifier::vertex(uint32_t id, const double xyz[3], const uint8_t* values) {
  if (id != received_ || id >= out_of_.size())
    return invalidData("simplification: vertex " + std::to_string(id) + " out of order or beyond the level");
  ++received_;
  if (!survives_[id]) return Status::ok();
  const uint32_t o = emitted_++;
  GTN_RETURN_IF_ERROR(out_.vertex(o, xyz, values));
  uint32_t slot = wait_head_[o];
  wait_head_[o] = wait_tail_[o] = kNoIndex;
  while (slot != kNoIndex) {
    const uint32_t next = held_[slot].next;
    GTN_RETURN_IF_ERROR(emitHeld(slot));
    slot = next;
  }
  return Status::ok();
}

Status StreamSimplifier::hold(const uint32_t* o, int count, bool triangle, const uint8_t* cell_values) {
  uint32_t slot;
  if (!free_slots_.empty()) {
    slot = free_slots_.back();
    free_slots_.pop_back();
  } else {
    slot = static_cast<uint32_t>(held_.size());
    held_.push_back({});
    held_values_.resize(held_values_.size() + cell_bytes_);
  }
  Held& h = held_[slot];
  h.triangle = triangle;
  h.next = kNoIndex;
  h.o[3] = kNoIndex;
  uint32_t last = 0;
  for (int i = 0; i < count; ++i) {
    h.o[i] = o[i];
    ++refs_[o[i]];
    last = std::max(last, o[i]);
  }
  if (wait_tail_[last] == kNoIndex) {
    wait_head_[last] = slot;
  } else {
    held_[wait_tail_[last]].next = slot;
  }
  wait_tail_[last] = slot;
  if (!triangle && cell_bytes_) std::memcpy(held_values_.data() + size_t{slot} * cell_bytes_, cell_values, cell_bytes_);
  peak_held_ = std::max(peak_held_, ++held_count_);
  return Status::ok();
}

Status StreamSimplifier::emitHeld(uint32_t slot) {
  const Held h = held_[slot];
  free_slots_.push_back(slot);
  --held_count_;
  if (h.triangle) {
    GTN_RETURN_IF_ERROR(out_.boundaryTriangle(h.o));
    ++out_triangles_;
  } else {
    GTN_RETURN_IF_ERROR(out_.tet(h.o, cell_bytes_ ? held_values_.data() + size_t{slot} * cell_bytes_ : nullptr));
    ++out_tets_;
  }
  for (int i = 0; i < (h.triangle ? 3 : 4); ++i) GTN_RETURN_IF_ERROR(release(h.o[i]));
  return Status::ok();
}

Status StreamSimplifier::release(uint32_t o) {
  if (refs_[o] == 0) return invalidData("simplification: output vertex " + std::to_string(o) + " retired twice");
  if (--refs_[o] == 0 && o < emitted_) return out_.retireVertex(o);
  return Status::ok();
}

Status StreamSimplifier::boundaryTriangle(const uint32_t v[3]) {
  if (!in_boundary_) return invalidData("simplification: boundary triangle after the end of the boundary");
  if (std::max({v[0], v[1], v[2]}) >= received_)
    return invalidData("simplification: boundary triangle refers to a vertex not yet emitted");
  const uint32_t o[3] = {out_of_[v[0]], out_of_[v[1]], out_of_[v[2]]};
  if (o[0] == o[1] || o[0] == o[2] || o[1] == o[2]) return Status::ok();
  if (std::max({o[0], o[1], o[2]}) < emitted_) {
    ++out_triangles_;
    return out_.boundaryTriangle(o);
  }
  return hold(o, 3, true, nullptr);
}

Status StreamSimplifier::endBoundary() {
  in_boundary_ = false;
  if (held_count_ != 0)
    return invalidData("simplification: the merge tree maps a boundary vertex to a vertex emitted after the boundary");
  if (out_triangles_ != out_header_.boundary_triangles)
    return invalidData("simplification: " + std::to_string(out_triangles_) +
                       " boundary triangles, the merge tree implies " + std::to_string(out_header_.boundary_triangles));
  return out_.endBoundary();
}

Status StreamSimplifier::tet(const uint32_t v[4], const uint8_t* cell_values) {
  if (std::max({v[0], v[1], v[2], v[3]}) >= received_)
    return invalidData("simplification: tetrahedron refers to a vertex not yet emitted");
  const uint32_t o[4] = {out_of_[v[0]], out_of_[v[1]], out_of_[v[2]], out_of_[v[3]]};
  if (o[0] == o[1] || o[0] == o[2] || o[0] == o[3] || o[1] == o[2] || o[1] == o[3] || o[2] == o[3]) {
    ++dropped_tets_;
    return Status::ok();
  }
  if (std::max({o[0], o[1], o[2], o[3]}) < emitted_) {
    ++out_tets_;
    return out_.tet(o, cell_values);
  }
  return hold(o, 4, false, cell_values);
}

Status StreamSimplifier::retireVertex(uint32_t id) {
  if (id >= received_) return invalidData("simplification: retirement of a vertex not yet emitted");
  return release(out_of_[id]);
}

Status StreamSimplifier::endLevel() {
  if (held_count_ != 0)
    return invalidData("simplification: " + std::to_string(held_count_) +
                       " tetrahedra still wait for vertices at the end of the level");
  if (received_ != in_header_.points) return invalidData("simplification: fewer vertices than the level header says");
  if (out_tets_ != out_header_.tets)
    return invalidData("simplification: " + std::to_string(out_tets_) + " tetrahedra, the merge tree implies " +
                       std::to_string(out_header_.tets));
  return out_.endLevel();
}

}  // namespace gtn
