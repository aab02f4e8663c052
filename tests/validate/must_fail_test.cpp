// One malformed input per error code of the registry, each with its expected report: exactly that
// error code and no other. Files come from the project's writer, mutated byte-wise or rebuilt chunk by
// chunk (validate_fixtures.h); defects the writer and coders cannot represent at all (a face in three
// tetrahedra, a merge-tree cycle the coder rejects by construction, ...) are fed to the layer that
// checks them as decoded content. A last test asserts that every error code has its case here.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>

#include "convert/export.h"
#include "mesh/hex_split.h"
#include "mesh/mesh_stats.h"
#include "simplify/apply.h"
#include "validate/mesh_checks.h"
#include "validate/validate_fixtures.h"

namespace gtn::test {
namespace {

// A small valid file (grid with two mip levels and merge trees), raw chunks, written once.
struct Base {
  std::string dir, path;
  TetMesh mesh;
  MergeTree tree;
  Bytes bytes;
};

const Base& base() {
  static Base b = [] {
    Base s;
    s.dir = tempDir("validate-must-fail");
    s.path = s.dir + "/base.gtn";
    s.mesh = makeGrid(4, 3, 3);
    StatusOr<MergeTree> tree = rankMerges(s.mesh, RankingOptions{}, nullptr);
    EXPECT_TRUE(tree.isOk());
    s.tree = *tree;
    writeValidGtn(s.path, s.mesh, 2, /*zstd=*/false);
    s.bytes = readBytes(s.path);
    return s;
  }();
  return b;
}

uint64_t loadU64(const Bytes& b, size_t at) {
  uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = v << 8 | b[at + i];
  return v;
}

// The offset of level `level`'s first chunk with `tag` in the base file.
uint64_t chunkOffset(int level, ChunkTag tag) {
  auto r = GtnReader::open(base().path);
  EXPECT_TRUE(r.isOk());
  for (const GtnChunkInfo& c : r.value()->level(level).chunks)
    if (c.tag == tag) return c.offset;
  ADD_FAILURE() << "no chunk " << tag.str();
  return 0;
}

Bytes rewrite(const std::function<void(std::vector<RewriteChunk>&)>& f) { return rewriteGtn(base().path, f); }

RewriteChunk& find(std::vector<RewriteChunk>& chunks, int level, ChunkTag tag) {
  for (RewriteChunk& c : chunks)
    if (c.level == level && c.tag == tag) return c;
  ADD_FAILURE() << "no chunk " << tag.str() << " in level " << level;
  return chunks.front();
}

// Writes a file from explicit level inputs (raw chunks).
Bytes writeLevels(const std::vector<GtnLevelInput>& levels) {
  const std::string path = base().dir + "/levels.gtn";
  GtnWriteOptions wo;
  wo.zstd = false;
  const Status st = writeGtnFile(path, levels, wo);
  EXPECT_TRUE(st.isOk()) << st.message();
  return readBytes(path);
}

// Codes `tree` against `mesh`, the level it belongs to (which must outlive the writer).
decltype(GtnLevelInput::merge_tree) treeCoder(const MergeTree& tree, const TetMesh& mesh) {
  return [tree, &mesh](const std::vector<uint32_t>& order) { return encodeMergeTree(tree, order, &mesh); };
}

// Level 0 + level 1 after n merges of `tree` (declared `declared` merges and ratio).
Bytes twoLevels(const MergeTree& tree, const TetMesh& level1, uint64_t declared, double ratio, bool with_tree) {
  GtnLevelInput l0;
  l0.mesh = &base().mesh;
  if (with_tree) l0.merge_tree = treeCoder(tree, base().mesh);
  GtnLevelInput l1;
  l1.mesh = &level1;
  l1.merges = declared;
  l1.ratio = ratio;
  return writeLevels({l0, l1});
}

TetMesh applied(const MergeTree& tree, uint64_t n) {
  StatusOr<TetMesh> m = applyMerges(base().mesh, tree, n);
  EXPECT_TRUE(m.isOk());
  return *m;
}

// The regular octahedron around an interior vertex 0 (vertices 1..6 = +x, -x, +y, -y, +z, -z): eight
// positive tetrahedra. `plus_x` moves vertex 1.
TetMesh octahedron(const double plus_x[3]) {
  TetMesh m;
  m.coords = {0, 0, 0, plus_x[0], plus_x[1], plus_x[2], -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
  for (uint32_t x : {1u, 2u})
    for (uint32_t y : {3u, 4u})
      for (uint32_t z : {5u, 6u}) m.tets.push_back({0, x, y, z});
  size_t zero = 0;
  normalizeOrientation(m, &zero);
  return m;
}

DecodedFile decodedOf(const TetMesh& mesh) {
  DecodedFile f;
  DecodedLevel l;
  l.mesh = mesh;
  l.header.points = mesh.numPoints();
  l.header.tets = mesh.numTets();
  const FaceAdjacency adj = computeFaceAdjacency(mesh);
  l.boundary = boundaryTriangles(mesh, adj);
  l.header.boundary_triangles = l.boundary.size();
  const MeshStats stats = computeMeshStats(mesh);
  for (int a = 0; a < 3; ++a) {
    l.header.bbox_min[a] = stats.bbox_min[a];
    l.header.bbox_max[a] = stats.bbox_max[a];
  }
  f.levels.push_back(std::move(l));
  return f;
}

MergeForest forestOf(const MergeTree& t) {
  MergeForest f;
  f.parent = t.parent;
  f.rank.assign(t.rank.begin(), t.rank.end());
  return f;
}

// Level 0 with a one-merge forest: vertex c into p.
DecodedFile withMerge(const TetMesh& mesh, uint32_t c, uint32_t p) {
  DecodedFile f = decodedOf(mesh);
  MergeForest forest;
  forest.parent.assign(mesh.numPoints(), kMergeRoot);
  forest.rank.assign(mesh.numPoints(), 0);
  forest.parent[c] = p;
  forest.rank[c] = 1;
  f.forest = forest;
  return f;
}

ValidationReport reportOf(const DecodedFile& f) {
  ValidationReport r(100);
  validateDecoded(f, {}, r);
  return r;
}

struct Case {
  std::function<Bytes()> file;                // a malformed file, or
  std::function<ValidationReport()> decoded;  // a report from decoded content
};

std::map<std::string, Case> cases() {
  std::map<std::string, Case> c;
  // Container.
  c["FILE_TOO_SMALL"].file = [] { return Bytes(base().bytes.begin(), base().bytes.begin() + 10); };
  c["BAD_MAGIC"].file = [] {
    Bytes b = base().bytes;
    b[1] = 'X';
    return b;
  };
  c["UNSUPPORTED_VERSION"].file = [] {
    Bytes b = base().bytes;
    const auto p = encodeGtnPrefix(kGtnMajorVersion + 1, 0);
    std::copy(p.begin(), p.end(), b.begin());
    return b;
  };
  c["CHECKSUM_MISMATCH"].file = [] {
    Bytes b = base().bytes;
    b[chunkOffset(0, kTagPiece) + kChunkFixedHeaderSize + 2] ^= 0x04;
    return b;
  };
  c["RESERVED_BITS_SET"].file = [] {
    Bytes b = base().bytes;
    b[kGtnPrefixSize + 4] |= 0x80;
    return b;
  };
  c["TRAILING_BYTES"].file = [] {
    Bytes b = base().bytes;
    b.push_back(0);
    return b;
  };
  c["CHUNK_FRAMING"].file = [] {
    Bytes b = base().bytes;
    b.resize(b.size() - 20);
    return b;
  };
  c["DIRECTORY_MISMATCH"].file = [] {
    Bytes b = base().bytes;
    const size_t end = b.size() - kGtnTrailerSize;
    GtnTrailer t;
    t.directory_offset = loadU64(b, end + kChunkFixedHeaderSize) + 1;
    t.directory_size = loadU64(b, end + kChunkFixedHeaderSize + 8);
    b.resize(end);
    appendGtnChunk(b, kTagEnd, encodeTrailer(t), false, false, 0);
    return b;
  };
  c["SIZE_OUT_OF_BOUNDS"].file = [] {
    return rewrite([](std::vector<RewriteChunk>& chunks) {
      GtnFileHeader h;
      ASSERT_TRUE(decodeFileHeader(chunks[0].payload, 0, "x", &h).isOk());
      h.level_count = kGtnMaxLevels + 1;
      chunks[0].payload = encodeFileHeader(h);
    });
  };
  c["MALFORMED_CONTAINER"].file = [] {
    return rewrite([](std::vector<RewriteChunk>& chunks) { std::swap(chunks[0], chunks[1]); });
  };
  // Decoding.
  c["NO_LEVELS"].decoded = [] { return reportOf(DecodedFile{}); };
  c["LEVEL_DECODE_FAILED"].file = [] {
    return rewrite([](std::vector<RewriteChunk>& chunks) {
      Bytes& p = find(chunks, 1, kTagPiece).streams.at(1);  // CONN
      p.resize(p.size() / 2);
    });
  };
  c["LEVEL_COUNT_MISMATCH"].decoded = [] {
    DecodedFile f = decodedOf(base().mesh);
    f.levels[0].header.tets += 1;
    return reportOf(f);
  };
  c["BOUNDING_BOX_MISMATCH"].decoded = [] {
    DecodedFile f = decodedOf(base().mesh);
    f.levels[0].header.bbox_max[1] += 1.0;  // a box taller than the points
    return reportOf(f);
  };
  c["BOUNDARY_MISMATCH"].decoded = [] {
    DecodedFile f = decodedOf(base().mesh);
    std::swap(f.levels[0].boundary[0][0], f.levels[0].boundary[0][1]);  // one triangle turned inwards
    return reportOf(f);
  };
  // Mesh.
  const double unit_x[3] = {1, 0, 0};
  const TetMesh octa = octahedron(unit_x);
  c["INVERTED_TET"].file = [octa] {
    static TetMesh m;
    m = octa;
    std::swap(m.tets[3][2], m.tets[3][3]);
    GtnLevelInput l0;
    l0.mesh = &m;
    return writeLevels({l0});
  };
  c["INDEX_OUT_OF_RANGE"].decoded = [octa] {
    DecodedFile f = decodedOf(octa);
    f.levels[0].mesh.tets[2][1] = 99;
    return reportOf(f);
  };
  c["REPEATED_VERTEX"].decoded = [octa] {
    DecodedFile f = decodedOf(octa);
    f.levels[0].mesh.tets[2][1] = f.levels[0].mesh.tets[2][0];
    return reportOf(f);
  };
  c["DUPLICATE_TET"].decoded = [octa] {
    TetMesh m = octa;
    m.tets = {octa.tets[0], octa.tets[0]};
    return reportOf(decodedOf(m));
  };
  c["NON_MANIFOLD_FACE"].decoded = [] {
    // Three positive tetrahedra on one triangle (two above it, one below).
    TetMesh m;
    m.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0.2, 0.2, 1, 0.3, 0.2, 2, 0.2, 0.3, -1};
    m.tets = {{0, 1, 2, 3}, {0, 1, 2, 4}, {0, 2, 1, 5}};
    return reportOf(decodedOf(m));
  };
  c["BOUNDARY_NOT_CLOSED"].decoded = [octa] {
    // The stored boundary surface with a hole: one of the octahedron's eight triangles left out.
    DecodedFile f = decodedOf(octa);
    EXPECT_EQ(f.levels[0].boundary.size(), 8u);
    f.levels[0].boundary.pop_back();
    f.levels[0].header.boundary_triangles = f.levels[0].boundary.size();
    return reportOf(f);
  };
  c["BOUNDARY_ORIENTATION"].decoded = [] {
    // Two positive tetrahedra on the same side of one shared triangle.
    TetMesh m;
    m.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0.2, 0.2, 1, 0.3, 0.2, 2};
    m.tets = {{0, 1, 2, 3}, {0, 1, 2, 4}};
    return reportOf(decodedOf(m));
  };
  c["NON_FINITE_COORDINATE"].decoded = [octa] {
    DecodedFile f = decodedOf(octa);
    f.levels[0].mesh.coords[4] = std::numeric_limits<double>::quiet_NaN();
    return reportOf(f);
  };
  c["FIELD_SIZE_MISMATCH"].decoded = [octa] {
    TetMesh m = octa;
    m.point_fields.emplace_back("rho", 1, ScalarType::kFloat32, m.numPoints() - 1);
    return reportOf(decodedOf(m));
  };
  // Merge tree.
  c["MERGE_TREE_UNDECODABLE"].file = [] {
    return rewrite([](std::vector<RewriteChunk>& chunks) { find(chunks, 0, kTagMergeTree).payload = {1, 200}; });
  };
  c["MERGE_TREE_SIZE"].decoded = [] {
    DecodedFile f = decodedOf(base().mesh);
    f.forest = forestOf(base().tree);
    f.forest->parent.pop_back();
    return reportOf(f);
  };
  c["MERGE_TREE_NOT_FOREST"].decoded = [] {
    DecodedFile f = decodedOf(base().mesh);
    f.forest = forestOf(base().tree);
    for (size_t v = 0; v < f.forest->parent.size(); ++v) {
      const uint32_t p = f.forest->parent[v];
      if (p != kMergeRoot && f.forest->parent[p] != kMergeRoot) {
        f.forest->parent[p] = static_cast<uint32_t>(v);  // v -> p -> v
        break;
      }
    }
    return reportOf(f);
  };
  c["MERGE_RANKS_NOT_PERMUTATION"].decoded = [] {
    DecodedFile f = decodedOf(base().mesh);
    f.forest = forestOf(base().tree);
    for (size_t v = 0; v < f.forest->parent.size(); ++v)
      if (f.forest->rank[v] == 2) f.forest->rank[v] = 1;
    return reportOf(f);
  };
  c["MERGE_NOT_ADJACENT"].decoded = [octa] { return reportOf(withMerge(octa, 1, 2)); };  // +x into -x
  c["MERGE_BOUNDARY_INTO_INTERIOR"].decoded = [octa] { return reportOf(withMerge(octa, 3, 0)); };
  c["MERGE_INVERTS_TET"].decoded = [] {
    const double w[3] = {1, 3, 0.5};
    return reportOf(withMerge(octahedron(w), 0, 1));
  };
  c["MERGE_FLATTENS_TET"].decoded = [] {
    const double w[3] = {1, 1, 1};  // on the plane of (-x, +y, +z)
    return reportOf(withMerge(octahedron(w), 0, 1));
  };
  c["MERGE_FLIPS_BOUNDARY"].decoded = [] {
    // Tetrahedra (c, t, b, d) and (c, b, e, d); merging c = 0 into t = 1 keeps (t, b, e, d) positive
    // but turns the boundary triangle (c, b, e), facing +z, to face -y.
    TetMesh m;
    m.coords = {0.5, 1, 0, -2, -0.5, 2, 0, 0, 0, 1, 0, 0, 0.5, 0.3, -1};
    m.tets = {{0, 1, 2, 4}, {0, 2, 3, 4}};
    size_t zero = 0;
    normalizeOrientation(m, &zero);
    return reportOf(withMerge(m, 0, 1));
  };
  c["MERGE_BREAKS_MANIFOLD"].decoded = [] {
    // (c, a, b, p) beside (t, a, b, q) and (t, a, b, r) on both sides of the triangle (t, a, b); c is
    // next to t through (c, t, x, y). Merging c = 0 into t = 1 puts (t, a, b) in three tetrahedra.
    // Level 0 itself touches along the edge (a, b), so only the merge-tree layer is run.
    TetMesh m;
    m.coords = {0,   0,   0.05, 0, 0,   0,   1,  0,  0, 0,   1, 0,  0.3, 0.3,
                0.5, 0.3, 0.3,  1, 0.3, 0.3, -1, -1, 0, 0.1, 0, -1, 0.1};
    m.tets = {{0, 1, 7, 8}, {0, 2, 3, 4}, {1, 2, 3, 5}, {1, 2, 3, 6}};
    size_t zero = 0;
    normalizeOrientation(m, &zero);
    ValidationReport r(100);
    checkMergeTree(m, *withMerge(m, 0, 1).forest, {}, r);
    return r;
  };
  c["MERGE_ANNOTATION_MISMATCH"].decoded = [] {
    DecodedFile f = decodedOf(base().mesh);
    f.forest = forestOf(base().tree);
    f.forest->removed = base().tree.removed;
    for (size_t v = 0; v < f.forest->parent.size(); ++v)
      if (f.forest->rank[v] == 1) f.forest->removed[v] += 1;
    return reportOf(f);
  };
  // Levels.
  c["LEVEL_MERGES_OUT_OF_RANGE"].file = [] {
    static TetMesh l1;
    l1 = applied(base().tree, base().tree.merges);
    return twoLevels(base().tree, l1, base().tree.merges + 1, 1.0, true);
  };
  c["LEVEL_MISMATCH"].file = [] {
    static TetMesh l1;
    const uint64_t n = base().tree.merges / 2;
    l1 = applied(base().tree, n + 1);
    return twoLevels(base().tree, l1, n, double(n) / base().mesh.numPoints(), true);
  };
  c["LEVEL_RATIO_MISMATCH"].file = [] {
    static TetMesh l1;
    const uint64_t n = base().tree.merges / 2;
    l1 = applied(base().tree, n);
    return twoLevels(base().tree, l1, n, 0.99, true);
  };
  c["LEVEL_WITHOUT_MERGE_TREE"].file = [] {
    static TetMesh l1;
    const uint64_t n = base().tree.merges / 2;
    l1 = applied(base().tree, n);
    return twoLevels(base().tree, l1, n, double(n) / base().mesh.numPoints(), false);
  };
  // Mesh files: a legacy VTK file whose CELLS list stops short.
  c["IMPORT_FAILED"].decoded = [] {
    const std::string path = base().dir + "/short-cells.vtk";
    writeFile(path,
              "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n"
              "0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 1 5\n4 0 1 2\n");
    StatusOr<ValidationReport> r = validateMeshFiles({path}, {});
    return r.isOk() ? std::move(r).value() : ValidationReport(100);
  };
  // --against.
  c["SOURCE_UNREADABLE"].decoded = [] {
    ValidationReport r(100);
    ValidateOptions o;
    o.against = {base().dir + "/no-such-source.vtk"};
    validateDecoded(decodedOf(base().mesh), o, r);
    return r;
  };
  c["SOURCE_COUNT_MISMATCH"].decoded = [] {
    ValidationReport r(100);
    TetMesh other = base().mesh;
    other.tets.pop_back();
    for (Field& f : other.cell_fields) f.bytes.resize(f.bytes.size() - f.components * f.valueSize());
    compareWithSource(base().mesh, other, r);
    return r;
  };
  c["SOURCE_FIELD_MISMATCH"].decoded = [] {
    ValidationReport r(100);
    TetMesh other = base().mesh;
    other.point_fields[0].name += "_renamed";
    compareWithSource(base().mesh, other, r);
    return r;
  };
  c["SOURCE_MESH_MISMATCH"].decoded = [] {
    ValidationReport r(100);
    TetMesh other = base().mesh;
    other.coords[3] = std::nextafter(other.coords[3], 1e300);
    compareWithSource(base().mesh, other, r);
    return r;
  };
  return c;
}

TEST(MustFail, BaseFileIsClean) {
  const ValidationReport r = validateBytesForTest(base().bytes);
  EXPECT_FALSE(r.hasErrors()) << r.toText("base.gtn");
}

TEST(MustFail, EachCaseGetsExactlyItsCode) {
  for (const auto& [code, c] : cases()) {
    SCOPED_TRACE(code);
    ValidationReport r = c.file ? validateBytesForTest(c.file()) : c.decoded();
    EXPECT_EQ(errorCodeSet(r), std::set<std::string>{code}) << r.toText(code);
  }
}

// Level 0 and a merge tree of one merge, vertex c into p, as a real file: the normal writer and coders,
// with the tree's annotations (boundary flag, tetrahedra removed) as the replay finds them, so that
// only the defect under test is reported. `extra_removed` falsifies the annotation.
Bytes oneMergeFile(const TetMesh& mesh, uint32_t c, uint32_t p, uint32_t extra_removed = 0) {
  MergeTree t;
  const size_t n = mesh.numPoints();
  t.makeRoots(n);
  t.parent[c] = p;
  t.rank[c] = 1;
  t.merges = 1;
  for (const Triangle& tri : boundaryTriangles(mesh, computeFaceAdjacency(mesh)))
    for (uint32_t v : tri) t.boundary[v] = t.boundary[v] || v == c;
  for (const Tet& tet : mesh.tets)
    if (std::count(tet.begin(), tet.end(), c) && std::count(tet.begin(), tet.end(), p)) ++t.removed[c];
  t.removed[c] += extra_removed;
  EXPECT_TRUE(t.check("one merge").isOk());
  GtnLevelInput l0;
  l0.mesh = &mesh;
  l0.merge_tree = treeCoder(t, mesh);
  return writeLevels({l0});
}

// The merge-layer defects the merge-tree coder can represent (all but a tree that is not a forest, ranks
// that are not a permutation and a size that differs, which its decoder rejects by construction), as
// .gtn files through the whole validator: each gets exactly its code.
TEST(MustFail, MergeDefectsAsFiles) {
  const double unit_x[3] = {1, 0, 0};
  const TetMesh octa = octahedron(unit_x);
  std::map<std::string, Bytes> files;
  files["MERGE_NOT_ADJACENT"] = oneMergeFile(octa, 1, 2);
  files["MERGE_BOUNDARY_INTO_INTERIOR"] = oneMergeFile(octa, 3, 0);
  const double w_invert[3] = {1, 3, 0.5}, w_flat[3] = {1, 1, 1};
  files["MERGE_INVERTS_TET"] = oneMergeFile(octahedron(w_invert), 0, 1);
  files["MERGE_FLATTENS_TET"] = oneMergeFile(octahedron(w_flat), 0, 1);
  {
    TetMesh m;  // as in cases(): the merge turns boundary triangle (c, b, e) from +z to -y
    m.coords = {0.5, 1, 0, -2, -0.5, 2, 0, 0, 0, 1, 0, 0, 0.5, 0.3, -1};
    m.tets = {{0, 1, 2, 4}, {0, 2, 3, 4}};
    size_t zero = 0;
    normalizeOrientation(m, &zero);
    files["MERGE_FLIPS_BOUNDARY"] = oneMergeFile(m, 0, 1);
  }
  {
    TetMesh m;  // as in cases(): level 0 touches along an edge, the merge puts a face in three tetrahedra
    m.coords = {0,   0,   0.05, 0, 0,   0,   1,  0,  0, 0,   1, 0,  0.3, 0.3,
                0.5, 0.3, 0.3,  1, 0.3, 0.3, -1, -1, 0, 0.1, 0, -1, 0.1};
    m.tets = {{0, 1, 7, 8}, {0, 2, 3, 4}, {1, 2, 3, 5}, {1, 2, 3, 6}};
    size_t zero = 0;
    normalizeOrientation(m, &zero);
    files["MERGE_BREAKS_MANIFOLD"] = oneMergeFile(m, 0, 1);
  }
  files["MERGE_ANNOTATION_MISMATCH"] = oneMergeFile(octa, 0, 1, /*extra_removed=*/1);
  // The same merge with true annotations is clean: the defects above are the merges', not the files'.
  const ValidationReport clean = validateBytesForTest(oneMergeFile(octa, 0, 1));
  EXPECT_FALSE(clean.hasErrors()) << clean.toText("octahedron, one merge");
  for (const auto& [code, bytes] : files) {
    SCOPED_TRACE(code);
    ASSERT_FALSE(bytes.empty());
    const ValidationReport r = validateBytesForTest(bytes);
    EXPECT_EQ(errorCodeSet(r), std::set<std::string>{code}) << r.toText(code);
  }
}

// The --against codes on the real path: the base file against sources written as .vtu files.
// Two tetrahedra touching along the edge (0, 1) only: the edge is in four boundary triangles. Merging
// 0 into 1 removes all four, while a reader, told only that the merge is a boundary merge, removes two
// and finds the boundary count wrong (`gtn export --merges` failed on such a TetGen mesh that the
// validator called valid). The flag and the count of removed tetrahedra are right; the merge is not.
TEST(MustFail, BoundaryMergeRemovingFourTrianglesIsAnAnnotationMismatch) {
  TetMesh m;
  m.coords = {0, 0, 0, 0, 0, 1, 1, 0, 0.5, 1, 1, 0.5, -1, 0, 0.5, -1, -1, 0.5};
  m.tets = {{0, 1, 2, 3}, {0, 1, 4, 5}};
  size_t zero = 0;
  normalizeOrientation(m, &zero);
  MergeForest forest = *withMerge(m, 0, 1).forest;
  forest.boundary.assign(m.numPoints(), 0);
  forest.removed.assign(m.numPoints(), 0);
  forest.boundary[0] = 1;
  forest.removed[0] = 2;
  ValidationReport r(100);
  checkMergeTree(m, forest, {}, r);
  EXPECT_EQ(r.errorCodes(), std::vector<std::string>{"MERGE_ANNOTATION_MISMATCH"}) << r.toText("edge");
  EXPECT_NE(r.toText("edge").find("removes 4 boundary triangles"), std::string::npos) << r.toText("edge");
}

TEST(MustFail, SourceDefectsAgainstFiles) {
  const auto against = [](const TetMesh& source, const std::string& name) {
    const std::string path = base().dir + "/" + name + ".vtu";
    EXPECT_TRUE(exportVtu(source, path, {}).isOk());
    ValidateOptions o;
    o.against = {path};
    return validateBytesForTest(base().bytes, o);
  };
  const ValidationReport same = against(base().mesh, "same");
  EXPECT_FALSE(same.hasErrors()) << same.toText("same");
  TetMesh moved = base().mesh;
  moved.coords[3] = std::nextafter(moved.coords[3], 1e300);
  EXPECT_EQ(errorCodeSet(against(moved, "moved")), std::set<std::string>{"SOURCE_MESH_MISMATCH"});
  TetMesh renamed = base().mesh;
  renamed.point_fields[0].name += "_renamed";
  EXPECT_EQ(errorCodeSet(against(renamed, "renamed")), std::set<std::string>{"SOURCE_FIELD_MISMATCH"});
  TetMesh fewer = base().mesh;
  fewer.tets.pop_back();
  for (Field& f : fewer.cell_fields) f.bytes.resize(f.bytes.size() - f.components * f.valueSize());
  EXPECT_EQ(errorCodeSet(against(fewer, "fewer")), std::set<std::string>{"SOURCE_COUNT_MISMATCH"});
  ValidateOptions missing;
  missing.against = {base().dir + "/no-such-source.vtu"};
  EXPECT_EQ(errorCodeSet(validateBytesForTest(base().bytes, missing)), std::set<std::string>{"SOURCE_UNREADABLE"});
}

TEST(MustFail, EveryErrorCodeHasACase) {
  const auto all = cases();
  for (const IssueInfo& info : allIssues()) {
    if (info.severity != Severity::kError) continue;
    EXPECT_TRUE(all.count(info.code)) << "no must-fail case for " << info.code;
  }
}

// Two unit cubes side by side sharing the four points of their common face, each cut into 5
// tetrahedra with the given parities: equal parities cut the common face along different diagonals
// (a non-conforming interface), opposite ones along the same.
TetMesh twoCubes(bool odd_first, bool odd_second, double lift = 0) {
  TetMesh m;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 3; ++i)
        m.coords.insert(m.coords.end(), {i + lift * (i == 1 && j == 1 && k == 1), double(j), double(k)});
  auto id = [](int i, int j, int k) { return static_cast<uint32_t>(i + 3 * (j + 2 * k)); };
  for (int c = 0; c < 2; ++c) {
    const uint32_t h[8] = {id(c, 0, 0), id(c + 1, 0, 0), id(c + 1, 1, 0), id(c, 1, 0),
                           id(c, 0, 1), id(c + 1, 0, 1), id(c + 1, 1, 1), id(c, 1, 1)};
    splitHexFive(h, c == 0 ? odd_first : odd_second, m.tets);
  }
  size_t zero = 0;
  normalizeOrientation(m, &zero);
  return m;
}

TEST(MustFail, NonconformingInterfaceIsAWarning) {
  // The common face cut along different diagonals: its four triangles are boundary faces covering the
  // same square from both sides. Closed and consistently oriented, so no error, but a warning that
  // names the four triangles.
  ValidationReport r = reportOf(decodedOf(twoCubes(false, false)));
  EXPECT_FALSE(r.hasErrors()) << r.toText("seam");
  EXPECT_EQ(r.count(IssueCode::kNonconformingInterface), 4u) << r.toText("seam");
  const std::string text = r.toText("seam");
  EXPECT_NE(text.find("NONCONFORMING_INTERFACE"), std::string::npos) << text;
  EXPECT_NE(text.find("4 boundary triangles that cover the same surface"), std::string::npos) << text;
  // Cut alike, the face is inside: nothing to report.
  ValidationReport ok = reportOf(decodedOf(twoCubes(false, true)));
  EXPECT_EQ(ok.count(IssueCode::kNonconformingInterface), 0u) << ok.toText("conforming");
  EXPECT_EQ(ok.count(Severity::kWarning), 0u) << ok.toText("conforming");
  // The common face's corner (1, 1, 1) moved out of its plane: the four triangles bound a thin
  // tetrahedron, as those of a cavity that a valid mesh may have do (below): not this pattern.
  EXPECT_EQ(reportOf(decodedOf(twoCubes(false, false, 0.25))).count(IssueCode::kNonconformingInterface), 0u);
  // A cube without its central tetrahedron: a cavity bounded by four boundary triangles, two on each
  // diagonal of a square of its faces' corners, but not coplanar.
  TetMesh cavity = twoCubes(false, true);
  cavity.tets.resize(5);
  cavity.tets.erase(cavity.tets.begin());
  ValidationReport c = reportOf(decodedOf(cavity));
  EXPECT_FALSE(c.hasErrors()) << c.toText("cavity");
  EXPECT_EQ(c.count(IssueCode::kNonconformingInterface), 0u) << c.toText("cavity");
}

TEST(MustFail, WarningsAndInfosKeepTheFileValid) {
  const double unit_x[3] = {1, 0, 0};
  TetMesh m = octahedron(unit_x);
  m.coords.insert(m.coords.end(), {5, 5, 5});  // an unreferenced point
  m.point_fields.emplace_back("rho", 1, ScalarType::kFloat32, m.numPoints());
  m.point_fields[0].set<float>(2, 0, std::numeric_limits<float>::infinity());
  ValidationReport r = reportOf(decodedOf(m));
  EXPECT_FALSE(r.hasErrors()) << r.toText("x");
  EXPECT_EQ(r.count(IssueCode::kUnreferencedPoint), 1u);
  EXPECT_EQ(r.count(IssueCode::kNonFiniteValue), 1u);
  EXPECT_EQ(r.count(IssueCode::kNoMergeTree), 1u);

  // Two tetrahedra sharing only an edge (as parts of Ossicles.vtu do): that edge is in four boundary
  // triangles, two each way; the surface is closed and consistently oriented.
  TetMesh pinched;
  pinched.coords = {0, 0, 0, 1, 0, 0, 0.5, 1, 0, 0.5, 0.5, 1, 0.5, -1, 0, 0.5, -0.5, -1};
  pinched.tets = {{0, 1, 2, 3}, {0, 1, 4, 5}};
  size_t pinched_zero = 0;
  normalizeOrientation(pinched, &pinched_zero);
  ValidationReport p = reportOf(decodedOf(pinched));
  EXPECT_FALSE(p.hasErrors()) << p.toText("pinched");

  // A flat tetrahedron is a warning.
  TetMesh flat;
  flat.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  flat.tets = {{0, 1, 2, 3}};
  ValidationReport f = reportOf(decodedOf(flat));
  EXPECT_FALSE(f.hasErrors()) << f.toText("flat");
  EXPECT_EQ(f.count(IssueCode::kZeroVolumeTet), 1u);

  // An ancillary chunk the validator does not know is an info.
  const Bytes b = rewrite([](std::vector<RewriteChunk>& chunks) {
    chunks.insert(chunks.begin() + 2, RewriteChunk{ChunkTag("ZZZZ"), 0, {1, 2, 3}, true, {}, {}});
  });
  ValidationReport u = validateBytesForTest(b);
  EXPECT_FALSE(u.hasErrors()) << u.toText("unknown");
  EXPECT_EQ(u.count(IssueCode::kUnknownChunk), 1u) << u.toText("unknown");
}

// Files of format 1.0 (never released) and of another draft revision of 2.0 are reported as an
// unsupported version, naming it.
TEST(MustFail, OlderVersionsAndOtherDraftsAreUnsupported) {
  Bytes v1 = base().bytes;
  const auto p = encodeGtnPrefix(1, 0);
  std::copy(p.begin(), p.end(), v1.begin());
  ValidationReport r = validateBytesForTest(v1);
  EXPECT_EQ(errorCodeSet(r), std::set<std::string>{"UNSUPPORTED_VERSION"}) << r.toText("v1");
  EXPECT_NE(r.toText("v1").find("format version 1.0"), std::string::npos) << r.toText("v1");
  const Bytes draft2 = rewrite([](std::vector<RewriteChunk>& chunks) {
    GtnFileHeader h;
    ASSERT_TRUE(decodeFileHeader(chunks[0].payload, 0, "x", &h).isOk());
    h.draft = 2;
    chunks[0].payload = encodeFileHeader(h);
  });
  r = validateBytesForTest(draft2);
  EXPECT_EQ(errorCodeSet(r), std::set<std::string>{"UNSUPPORTED_VERSION"}) << r.toText("d2");
  EXPECT_NE(r.toText("d2").find("draft revision 2"), std::string::npos) << r.toText("d2");
}

}  // namespace
}  // namespace gtn::test
