// Helpers shared by the simplification tests: synthetic meshes, a simple stream emitter, mesh
// invariants and the comparison of a streamed result with the in-memory reference.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "codec/level_codec.h"
#include "codec/merge_tree_coder.h"
#include "mesh/faces.h"
#include "mesh/hex_split.h"
#include "mesh/mesh_stats.h"
#include "mesh/mesh_stream.h"
#include "mesh/predicates.h"
#include "simplify/apply.h"
#include "simplify/stream_simplifier.h"

namespace gtn::test {

// A structured grid of nx*ny*nz cells split into six tetrahedra each, slightly perturbed, with a
// smooth density "rho" and the original vertex index "id" (float64) as point fields.
inline TetMesh makeGrid(int nx, int ny, int nz, uint32_t seed = 1) {
  TetMesh m;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.15, 0.15);
  auto idx = [&](int i, int j, int k) { return static_cast<uint32_t>((k * (ny + 1) + j) * (nx + 1) + i); };
  const size_t np = size_t(nx + 1) * (ny + 1) * (nz + 1);
  Field rho("rho", 1, ScalarType::kFloat64, np), id("id", 1, ScalarType::kFloat64, np);
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        const bool inner = i > 0 && i < nx && j > 0 && j < ny && k > 0 && k < nz;
        const double x = i + (inner ? jitter(rng) : 0), y = j + (inner ? jitter(rng) : 0),
                     z = k + (inner ? jitter(rng) : 0);
        m.coords.insert(m.coords.end(), {x, y, z});
        const uint32_t v = idx(i, j, k);
        rho.set<double>(v, 0, 1.0 + std::sin(0.4 * x) * std::cos(0.3 * y) + 0.05 * z * z);
        id.set<double>(v, 0, double(v));
      }
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const uint32_t h[8] = {idx(i, j, k),     idx(i + 1, j, k),     idx(i + 1, j + 1, k),     idx(i, j + 1, k),
                               idx(i, j, k + 1), idx(i + 1, j, k + 1), idx(i + 1, j + 1, k + 1), idx(i, j + 1, k + 1)};
        splitHexSix(h, m.tets);
      }
  m.point_fields.push_back(std::move(rho));
  m.point_fields.push_back(std::move(id));
  Field region("region", 1, ScalarType::kInt32, m.tets.size());
  for (size_t t = 0; t < m.tets.size(); ++t) region.set<int32_t>(t, 0, int32_t(t % 7));
  m.cell_fields.push_back(std::move(region));
  size_t zero = 0;
  normalizeOrientation(m, &zero);
  return m;
}

// Emits `mesh` as a mesh stream with vertex ids vertex_order[v]: boundary vertices and triangles
// first, then tetrahedra in an order that makes vertices arrive late (sorted by the largest id),
// each vertex just before its first tetrahedron, each retired after its last one.
inline Status emitMesh(const TetMesh& mesh, const std::vector<uint32_t>& vertex_order, MeshSink& sink) {
  const size_t np = mesh.numPoints();
  std::vector<uint32_t> inverse(np);
  for (size_t v = 0; v < np; ++v) inverse[vertex_order[v]] = static_cast<uint32_t>(v);
  const FaceAdjacency adj = computeFaceAdjacency(mesh);
  const std::vector<Triangle> tris = boundaryTriangles(mesh, adj);
  std::vector<uint8_t> is_b(np, 0);
  for (const Triangle& t : tris)
    for (uint32_t v : t) is_b[v] = 1;
  // Stream ids: boundary vertices first (by vertex_order), then the rest.
  std::vector<uint32_t> order;
  for (uint32_t id = 0; id < np; ++id)
    if (is_b[inverse[id]]) order.push_back(inverse[id]);
  const size_t nb = order.size();
  for (uint32_t id = 0; id < np; ++id)
    if (!is_b[inverse[id]]) order.push_back(inverse[id]);
  std::vector<uint32_t> sid(np);
  for (size_t i = 0; i < np; ++i) sid[order[i]] = static_cast<uint32_t>(i);
  LevelHeader h;
  h.points = np;
  h.tets = mesh.numTets();
  h.boundary_triangles = tris.size();
  h.coord_type = mesh.coord_type;
  for (const Field& f : mesh.point_fields) h.point_fields.push_back({f.name, f.components, f.type});
  for (const Field& f : mesh.cell_fields) h.cell_fields.push_back({f.name, f.components, f.type});
  GTN_RETURN_IF_ERROR(sink.beginLevel(h));
  size_t point_bytes = 0, cell_bytes = 0;
  for (const FieldDesc& d : h.point_fields) point_bytes += d.itemBytes();
  for (const FieldDesc& d : h.cell_fields) cell_bytes += d.itemBytes();
  std::vector<uint8_t> buf(std::max(point_bytes, cell_bytes) + 1);
  uint32_t next = 0;
  auto emitVertex = [&](uint32_t v) {
    uint8_t* p = buf.data();
    for (const Field& f : mesh.point_fields) {
      const size_t n = f.components * f.valueSize();
      std::memcpy(p, f.bytes.data() + v * n, n);
      p += n;
    }
    return sink.vertex(next++, mesh.point(v), buf.data());
  };
  for (size_t i = 0; i < nb; ++i) GTN_RETURN_IF_ERROR(emitVertex(order[i]));
  for (const Triangle& t : tris) {
    const uint32_t v[3] = {sid[t[0]], sid[t[1]], sid[t[2]]};
    GTN_RETURN_IF_ERROR(sink.boundaryTriangle(v));
  }
  GTN_RETURN_IF_ERROR(sink.endBoundary());
  std::vector<size_t> tet_order(mesh.numTets());
  for (size_t t = 0; t < tet_order.size(); ++t) tet_order[t] = t;
  auto key = [&](size_t t) {
    uint32_t m = 0;
    for (uint32_t v : mesh.tets[t]) m = std::max(m, sid[v]);
    return m;
  };
  std::stable_sort(tet_order.begin(), tet_order.end(), [&](size_t a, size_t b) { return key(a) < key(b); });
  std::vector<uint32_t> uses(np, 0);
  for (const Tet& t : mesh.tets)
    for (uint32_t v : t) ++uses[v];
  for (size_t t : tet_order) {
    for (uint32_t v : mesh.tets[t]) {
      while (next <= sid[v]) GTN_RETURN_IF_ERROR(emitVertex(order[next]));
    }
    const uint32_t v[4] = {sid[mesh.tets[t][0]], sid[mesh.tets[t][1]], sid[mesh.tets[t][2]], sid[mesh.tets[t][3]]};
    uint8_t* p = buf.data();
    for (const Field& f : mesh.cell_fields) {
      const size_t n = f.components * f.valueSize();
      std::memcpy(p, f.bytes.data() + t * n, n);
      p += n;
    }
    GTN_RETURN_IF_ERROR(sink.tet(v, buf.data()));
    for (uint32_t x : mesh.tets[t]) {
      if (--uses[x] == 0) GTN_RETURN_IF_ERROR(sink.retireVertex(sid[x]));
    }
  }
  while (next < np) GTN_RETURN_IF_ERROR(emitVertex(order[next]));
  // Stream ids are what a tree for this stream must be numbered in.
  return sink.endLevel();
}

// The stream ids emitMesh gives (boundary vertices first by vertex_order, then the rest).
inline std::vector<uint32_t> emitterIds(const TetMesh& mesh, const std::vector<uint32_t>& vertex_order) {
  const size_t np = mesh.numPoints();
  std::vector<uint32_t> inverse(np);
  for (size_t v = 0; v < np; ++v) inverse[vertex_order[v]] = static_cast<uint32_t>(v);
  const FaceAdjacency adj = computeFaceAdjacency(mesh);
  std::vector<uint8_t> is_b(np, 0);
  for (const Triangle& t : boundaryTriangles(mesh, adj))
    for (uint32_t v : t) is_b[v] = 1;
  std::vector<uint32_t> sid(np);
  uint32_t next = 0;
  for (uint32_t id = 0; id < np; ++id)
    if (is_b[inverse[id]]) sid[inverse[id]] = next++;
  for (uint32_t id = 0; id < np; ++id)
    if (!is_b[inverse[id]]) sid[inverse[id]] = next++;
  return sid;
}

struct MeshChecks {
  uint64_t inverted = 0, zero_volume = 0, non_manifold = 0, duplicates = 0;
  long boundary_euler = 0;
  uint64_t boundary_triangles = 0;
};

// `mesh` with vertex v numbered order[v] (points and tetrahedra only): the mesh a decoder that gives v
// the id order[v] sees, which a version 3 merge tree is decoded against.
inline TetMesh renumberedMesh(const TetMesh& mesh, const std::vector<uint32_t>& order) {
  TetMesh out;
  out.coords.resize(mesh.coords.size());
  for (size_t v = 0; v < mesh.numPoints(); ++v)
    for (int k = 0; k < 3; ++k) out.coords[3 * size_t{order[v]} + k] = mesh.coords[3 * v + k];
  for (const Tet& t : mesh.tets) out.tets.push_back({order[t[0]], order[t[1]], order[t[2]], order[t[3]]});
  return out;
}

inline long eulerOfTriangles(const std::vector<Triangle>& tris) {
  std::set<uint32_t> verts;
  std::set<std::pair<uint32_t, uint32_t>> edges;
  for (const Triangle& t : tris) {
    for (int i = 0; i < 3; ++i) {
      verts.insert(t[i]);
      edges.insert({std::min(t[i], t[(i + 1) % 3]), std::max(t[i], t[(i + 1) % 3])});
    }
  }
  return long(verts.size()) - long(edges.size()) + long(tris.size());
}

inline MeshChecks checkMesh(const TetMesh& m) {
  MeshChecks c;
  std::vector<std::array<uint32_t, 4>> sorted;
  for (const Tet& t : m.tets) {
    const int o = orient3d(m.point(t[0]), m.point(t[1]), m.point(t[2]), m.point(t[3]));
    c.inverted += o < 0;
    c.zero_volume += o == 0;
    std::array<uint32_t, 4> s = t;
    std::sort(s.begin(), s.end());
    sorted.push_back(s);
  }
  std::sort(sorted.begin(), sorted.end());
  for (size_t i = 1; i < sorted.size(); ++i) c.duplicates += sorted[i] == sorted[i - 1];
  const FaceAdjacency adj = computeFaceAdjacency(m);
  c.non_manifold = adj.non_manifold_faces;
  const std::vector<Triangle> tris = boundaryTriangles(m, adj);
  c.boundary_triangles = tris.size();
  c.boundary_euler = eulerOfTriangles(tris);
  return c;
}

// Tetrahedra of `m` as sorted tuples of the "id" point field (the source vertex index).
inline std::vector<std::array<uint64_t, 4>> tetsById(const TetMesh& m, const std::vector<uint64_t>& ids) {
  std::vector<std::array<uint64_t, 4>> out;
  for (const Tet& t : m.tets) {
    std::array<uint64_t, 4> a{ids[t[0]], ids[t[1]], ids[t[2]], ids[t[3]]};
    std::sort(a.begin(), a.end());
    out.push_back(a);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Triangles as id triples rotated so the smallest id comes first (keeps orientation).
inline std::vector<std::array<uint64_t, 3>> trianglesById(const std::vector<Triangle>& tris,
                                                          const std::vector<uint64_t>& ids) {
  std::vector<std::array<uint64_t, 3>> out;
  for (const Triangle& t : tris) {
    std::array<uint64_t, 3> a{ids[t[0]], ids[t[1]], ids[t[2]]};
    while (a[0] > a[1] || a[0] > a[2]) std::rotate(a.begin(), a.begin() + 1, a.end());
    out.push_back(a);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Vertex identity for comparisons: the "id" field when present, else the coordinates' rank.
inline std::vector<uint64_t> vertexIds(const TetMesh& m) {
  std::vector<uint64_t> ids(m.numPoints());
  if (const Field* f = m.findPointField("id")) {
    for (size_t v = 0; v < ids.size(); ++v) ids[v] = static_cast<uint64_t>(f->get(v, 0));
  } else {
    for (size_t v = 0; v < ids.size(); ++v) ids[v] = v;
  }
  return ids;
}

// Adds an "id" point field (float64 source index) so that streamed vertices can be identified.
inline void addIdField(TetMesh& m) {
  if (m.findPointField("id")) return;
  Field id("id", 1, ScalarType::kFloat64, m.numPoints());
  for (size_t v = 0; v < m.numPoints(); ++v) id.set<double>(v, 0, double(v));
  m.point_fields.push_back(std::move(id));
}

// Records the stream the simplifier produces (checks the order contract on the way).
class RecordingSink : public TetMeshBuilder {
 public:
  Status endBoundary() override {
    boundary_done = true;
    return Status::ok();
  }
  Status vertex(uint32_t id, const double xyz[3], const uint8_t* values) override {
    live.insert(id);
    return TetMeshBuilder::vertex(id, xyz, values);
  }
  Status tet(const uint32_t v[4], const uint8_t* cell_values) override {
    for (int i = 0; i < 4; ++i)
      if (!live.count(v[i])) ++use_of_dead;
    return TetMeshBuilder::tet(v, cell_values);
  }
  Status boundaryTriangle(const uint32_t v[3]) override {
    if (boundary_done) ++late_triangles;
    for (int i = 0; i < 3; ++i)
      if (!live.count(v[i])) ++use_of_dead;
    return TetMeshBuilder::boundaryTriangle(v);
  }
  Status retireVertex(uint32_t id) override {
    if (!live.erase(id)) ++bad_retire;
    ++retired;
    return Status::ok();
  }
  std::set<uint32_t> live;
  bool boundary_done = false;
  uint64_t use_of_dead = 0, bad_retire = 0, late_triangles = 0, retired = 0;
};

// Streams `mesh` through a StreamSimplifier with the first n merges of `tree` (source numbering),
// through the level codec when `use_codec`, else through emitMesh with a shuffled order, and checks
// that the result equals applyMerges(mesh, tree, n). `mesh` must carry the "id" field.
// `encoded` (optional) is encodeLevel(mesh), to encode a big mesh once for many n.
inline void expectStreamMatchesApply(const TetMesh& mesh, const MergeTree& tree, uint64_t n, bool use_codec,
                                     const EncodedLevel* encoded = nullptr) {
  SCOPED_TRACE("n = " + std::to_string(n) + (use_codec ? " (codec)" : " (emitter)"));
  auto applied = applyMerges(mesh, tree, n);
  ASSERT_TRUE(applied.isOk()) << applied.status().message();
  RecordingSink rec;
  if (use_codec) {
    StatusOr<EncodedLevel> own = encoded ? StatusOr<EncodedLevel>(Status::ok()) : encodeLevel(mesh, EncodeOptions{});
    ASSERT_TRUE(encoded || own.isOk()) << own.status().message();
    const EncodedLevel* enc = encoded ? encoded : &own.value();
    auto payload = encodeMergeTree(tree, enc->vertex_order, &mesh);
    ASSERT_TRUE(payload.isOk()) << payload.status().message();
    const TetMesh decoded = renumberedMesh(mesh, enc->vertex_order);
    auto stream_tree = decodeMergeTree(*payload, mesh.numPoints(), "test", &decoded);
    ASSERT_TRUE(stream_tree.isOk()) << stream_tree.status().message();
    StreamSimplifier simp(*stream_tree, n, rec);
    Status st = decodeLevel(enc->header, payloadOf(*enc), simp, nullptr, "test");
    ASSERT_TRUE(st.isOk()) << st.message();
  } else {
    std::vector<uint32_t> perm(mesh.numPoints());
    for (size_t i = 0; i < perm.size(); ++i) perm[i] = static_cast<uint32_t>(i);
    std::mt19937 rng(static_cast<uint32_t>(n) + 7);
    std::shuffle(perm.begin(), perm.end(), rng);
    const std::vector<uint32_t> sid = emitterIds(mesh, perm);
    auto payload = encodeMergeTree(tree, sid, &mesh);
    ASSERT_TRUE(payload.isOk()) << payload.status().message();
    const TetMesh decoded = renumberedMesh(mesh, sid);
    auto stream_tree = decodeMergeTree(*payload, mesh.numPoints(), "test", &decoded);
    ASSERT_TRUE(stream_tree.isOk()) << stream_tree.status().message();
    StreamSimplifier simp(*stream_tree, n, rec);
    Status st = emitMesh(mesh, perm, simp);
    ASSERT_TRUE(st.isOk()) << st.message();
    EXPECT_EQ(rec.retired, applied->numPoints());
    EXPECT_TRUE(rec.live.empty());
  }
  EXPECT_EQ(rec.use_of_dead, 0u);
  EXPECT_EQ(rec.bad_retire, 0u);
  EXPECT_EQ(rec.late_triangles, 0u);
  const TetMesh& got = rec.mesh();
  EXPECT_EQ(got.numPoints(), applied->numPoints());
  EXPECT_EQ(got.numTets(), applied->numTets());
  EXPECT_EQ(rec.header().points, got.numPoints());
  EXPECT_EQ(rec.header().tets, got.numTets());
  const std::vector<uint64_t> got_ids = vertexIds(got), want_ids = vertexIds(*applied);
  EXPECT_EQ(tetsById(got, got_ids), tetsById(*applied, want_ids));
  std::vector<Triangle> got_tris(rec.boundary().begin(), rec.boundary().end());
  const std::vector<Triangle> want_tris = boundaryTriangles(*applied, computeFaceAdjacency(*applied));
  EXPECT_EQ(rec.header().boundary_triangles, got_tris.size());
  EXPECT_EQ(trianglesById(got_tris, got_ids), trianglesById(want_tris, want_ids));
  for (const Tet& t : got.tets) {
    EXPECT_GE(orient3d(got.point(t[0]), got.point(t[1]), got.point(t[2]), got.point(t[3])), 0);
  }
}

}  // namespace gtn::test
