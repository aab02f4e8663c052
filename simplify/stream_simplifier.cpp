#include "simplify/stream_simplifier.h"

#include <algorithm>
#include <cstring>

#include "simplify/apply.h"

namespace gtn {

namespace {
constexpr uint32_t kUnset = 0xFFFFFFFFu;
}

StreamSimplifier::StreamSimplifier(const MergeTree& tree, uint64_t n, MeshSink& out)
    : tree_(tree), n_(std::min<uint64_t>(n, tree.merges)), out_(out) {}

Status StreamSimplifier::beginLevel(const LevelHeader& header) {
  if (header.points != tree_.points())
    return invalidData("simplification: the level has " + std::to_string(header.points) +
                       " vertices, its merge tree " + std::to_string(tree_.points()));
  GTN_RETURN_IF_ERROR(tree_.check("simplification: merge tree"));
  in_header_ = header;
  cell_bytes_ = 0;
  for (const FieldDesc& d : header.cell_fields) cell_bytes_ += d.itemBytes();
  ancestor_ = computeAncestors(tree_, n_);
  const size_t np = tree_.points();
  out_id_.assign(np, kUnset);
  refs_.assign(np, 0);
  for (size_t v = 0; v < np; ++v) ++refs_[ancestor_[v]];
  received_ = emitted_ = 0;
  out_tets_ = out_triangles_ = dropped_tets_ = 0;
  held_.clear();
  held_values_.clear();
  free_slots_.clear();
  wait_head_.assign(np, kUnset);
  wait_tail_.assign(np, kUnset);
  wait_nodes_.clear();
  free_nodes_.clear();
  held_count_ = peak_held_ = 0;
  in_boundary_ = true;
  out_header_ = header;
  out_header_.merges = header.merges + n_;
  out_header_.points = header.points - n_;
  const uint64_t removed = tree_.tetsRemovedUpTo(n_);
  const uint64_t boundary_removed = 2 * tree_.boundaryMergesUpTo(n_);
  if (removed > header.tets || boundary_removed > header.boundary_triangles)
    return invalidData("simplification: the merge tree removes more elements than the level has");
  out_header_.tets = header.tets - removed;
  out_header_.boundary_triangles = header.boundary_triangles - boundary_removed;
  return out_.beginLevel(out_header_);
}

Status StreamSimplifier::vertex(uint32_t id, const double xyz[3], const uint8_t* values) {
  if (id != received_ || id >= ancestor_.size())
    return invalidData("simplification: vertex " + std::to_string(id) + " out of order or beyond the level");
  ++received_;
  if (ancestor_[id] != id) return Status::ok();
  out_id_[id] = emitted_;
  GTN_RETURN_IF_ERROR(out_.vertex(emitted_++, xyz, values));
  uint32_t node = wait_head_[id];
  wait_head_[id] = wait_tail_[id] = kUnset;
  while (node != kUnset) {
    const WaitNode w = wait_nodes_[node];
    free_nodes_.push_back(node);
    if (--held_[w.slot].missing == 0) GTN_RETURN_IF_ERROR(emitHeld(w.slot));
    node = w.next;
  }
  return Status::ok();
}

Status StreamSimplifier::hold(const uint32_t* anc, int count, bool triangle, const uint8_t* cell_values) {
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
  h.missing = 0;
  h.v[3] = kUnset;
  for (int i = 0; i < count; ++i) {
    h.v[i] = anc[i];
    ++refs_[anc[i]];
    if (out_id_[anc[i]] == kUnset) {
      ++h.missing;
      uint32_t node;
      if (!free_nodes_.empty()) {
        node = free_nodes_.back();
        free_nodes_.pop_back();
      } else {
        node = static_cast<uint32_t>(wait_nodes_.size());
        wait_nodes_.push_back({});
      }
      wait_nodes_[node] = {slot, kUnset};
      if (wait_tail_[anc[i]] == kUnset) {
        wait_head_[anc[i]] = node;
      } else {
        wait_nodes_[wait_tail_[anc[i]]].next = node;
      }
      wait_tail_[anc[i]] = node;
    }
  }
  if (!triangle && cell_bytes_) std::memcpy(held_values_.data() + size_t{slot} * cell_bytes_, cell_values, cell_bytes_);
  peak_held_ = std::max(peak_held_, ++held_count_);
  return Status::ok();
}

Status StreamSimplifier::emitHeld(uint32_t slot) {
  Held h = held_[slot];
  free_slots_.push_back(slot);
  --held_count_;
  if (h.triangle) {
    const uint32_t o[3] = {out_id_[h.v[0]], out_id_[h.v[1]], out_id_[h.v[2]]};
    GTN_RETURN_IF_ERROR(out_.boundaryTriangle(o));
    ++out_triangles_;
  } else {
    const uint32_t o[4] = {out_id_[h.v[0]], out_id_[h.v[1]], out_id_[h.v[2]], out_id_[h.v[3]]};
    GTN_RETURN_IF_ERROR(out_.tet(o, cell_bytes_ ? held_values_.data() + size_t{slot} * cell_bytes_ : nullptr));
    ++out_tets_;
  }
  for (int i = 0; i < (h.triangle ? 3 : 4); ++i) GTN_RETURN_IF_ERROR(release(h.v[i]));
  return Status::ok();
}

Status StreamSimplifier::release(uint32_t a) {
  if (refs_[a] == 0) return invalidData("simplification: vertex " + std::to_string(a) + " retired twice");
  if (--refs_[a] == 0 && out_id_[a] != kUnset) return out_.retireVertex(out_id_[a]);
  return Status::ok();
}

Status StreamSimplifier::boundaryTriangle(const uint32_t v[3]) {
  if (!in_boundary_) return invalidData("simplification: boundary triangle after the end of the boundary");
  uint32_t a[3];
  for (int i = 0; i < 3; ++i) {
    if (v[i] >= received_) return invalidData("simplification: boundary triangle refers to a vertex not yet emitted");
    a[i] = ancestor_[v[i]];
  }
  if (a[0] == a[1] || a[0] == a[2] || a[1] == a[2]) return Status::ok();
  if (out_id_[a[0]] != kUnset && out_id_[a[1]] != kUnset && out_id_[a[2]] != kUnset) {
    const uint32_t o[3] = {out_id_[a[0]], out_id_[a[1]], out_id_[a[2]]};
    ++out_triangles_;
    return out_.boundaryTriangle(o);
  }
  return hold(a, 3, true, nullptr);
}

Status StreamSimplifier::endBoundary() {
  in_boundary_ = false;
  if (held_count_ != 0)
    return invalidData("simplification: the merge tree maps a boundary vertex to a vertex emitted after the boundary");
  if (out_triangles_ != out_header_.boundary_triangles)
    return invalidData("simplification: " + std::to_string(out_triangles_) + " boundary triangles, the merge tree implies " +
                       std::to_string(out_header_.boundary_triangles));
  return out_.endBoundary();
}

Status StreamSimplifier::tet(const uint32_t v[4], const uint8_t* cell_values) {
  uint32_t a[4];
  for (int i = 0; i < 4; ++i) {
    if (v[i] >= received_) return invalidData("simplification: tetrahedron refers to a vertex not yet emitted");
    a[i] = ancestor_[v[i]];
  }
  if (a[0] == a[1] || a[0] == a[2] || a[0] == a[3] || a[1] == a[2] || a[1] == a[3] || a[2] == a[3]) {
    ++dropped_tets_;
    return Status::ok();
  }
  if (out_id_[a[0]] != kUnset && out_id_[a[1]] != kUnset && out_id_[a[2]] != kUnset && out_id_[a[3]] != kUnset) {
    const uint32_t o[4] = {out_id_[a[0]], out_id_[a[1]], out_id_[a[2]], out_id_[a[3]]};
    ++out_tets_;
    return out_.tet(o, cell_values);
  }
  return hold(a, 4, false, cell_values);
}

Status StreamSimplifier::retireVertex(uint32_t id) {
  if (id >= received_) return invalidData("simplification: retirement of a vertex not yet emitted");
  return release(ancestor_[id]);
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
