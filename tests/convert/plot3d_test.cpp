// PLOT3D import: the paper's real datasets (bit-exact against an independent read, Table 1 counts),
// synthetic files of every layout the detector must tell apart, bad input, --weld, the .p3d
// meta-file, the sample generator and the CLI.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <nlohmann/json.hpp>

#include "convert/import.h"
#include "mesh/faces.h"
#include "mesh/mesh_stats.h"
#include "mesh/predicates.h"
#include "test_util.h"
#include "validate/mesh_checks.h"

namespace gtn {
namespace {

using test::dataPath;

// ---- Independent big-endian reads of the data files -------------------------------------------

uint32_t be32(const std::string& bytes, size_t offset) {
  return (static_cast<uint32_t>(static_cast<unsigned char>(bytes[offset])) << 24) |
         (static_cast<uint32_t>(static_cast<unsigned char>(bytes[offset + 1])) << 16) |
         (static_cast<uint32_t>(static_cast<unsigned char>(bytes[offset + 2])) << 8) |
         static_cast<uint32_t>(static_cast<unsigned char>(bytes[offset + 3]));
}

uint32_t fieldBits32(const Field& f, size_t item, uint32_t comp) {
  uint32_t v;
  std::memcpy(&v, f.bytes.data() + (item * f.components + comp) * 4, 4);
  return v;
}

StatusOr<ImportResult> importFiles(const std::vector<std::string>& files, int split = 6, bool weld = false) {
  ImportOptions o;
  o.split = split;
  o.weld = weld;
  return importMesh(files, o);
}

// Checks every coordinate and every Q value of a real dataset against the raw big-endian file; the
// `added` Steiner points of warped cells come after the file's points.
void expectBitExact(const ImportResult& r, const std::string& xyz_path, const std::string& q_path, size_t added = 0) {
  const std::string xyz = test::readFile(xyz_path), q = test::readFile(q_path);
  const size_t n = static_cast<size_t>(be32(xyz, 0)) * be32(xyz, 4) * be32(xyz, 8);
  ASSERT_EQ(r.mesh.numPoints(), n + added);
  ASSERT_EQ(r.mesh.coord_type, ScalarType::kFloat32);
  size_t coord_mismatch = 0;
  for (size_t p = 0; p < n; ++p) {
    for (int a = 0; a < 3; ++a) {
      const float expected = std::bit_cast<float>(be32(xyz, 12 + 4 * (a * n + p)));
      if (std::bit_cast<uint64_t>(r.mesh.coords[3 * p + a]) != std::bit_cast<uint64_t>(static_cast<double>(expected)))
        ++coord_mismatch;
    }
  }
  EXPECT_EQ(coord_mismatch, 0u);
  const Field* density = r.mesh.findPointField("density");
  const Field* momentum = r.mesh.findPointField("momentum");
  const Field* energy = r.mesh.findPointField("stagnation_energy");
  ASSERT_TRUE(density && momentum && energy);
  EXPECT_EQ(density->type, ScalarType::kFloat32);
  EXPECT_EQ(density->components, 1u);
  EXPECT_EQ(momentum->components, 3u);
  EXPECT_EQ(energy->components, 1u);
  ASSERT_EQ(density->itemCount(), n + added);
  ASSERT_EQ(momentum->itemCount(), n + added);
  ASSERT_EQ(energy->itemCount(), n + added);
  const size_t data = 12 + 16;
  size_t q_mismatch = 0;
  for (size_t p = 0; p < n; ++p) {
    q_mismatch += fieldBits32(*density, p, 0) != be32(q, data + 4 * p);
    for (uint32_t c = 0; c < 3; ++c)
      q_mismatch += fieldBits32(*momentum, p, c) != be32(q, data + 4 * ((1 + c) * n + p));
    q_mismatch += fieldBits32(*energy, p, 0) != be32(q, data + 4 * (4 * n + p));
  }
  EXPECT_EQ(q_mismatch, 0u);
  static const char* kKeys[4] = {"plot3d.fsmach", "plot3d.alpha", "plot3d.re", "plot3d.time"};
  for (int k = 0; k < 4; ++k) {
    const std::string* v = r.mesh.findMetadata(kKeys[k]);
    ASSERT_TRUE(v) << kKeys[k];
    EXPECT_EQ(std::bit_cast<uint32_t>(std::stof(*v)), be32(q, 12 + 4 * k)) << kKeys[k] << " = " << *v;
  }
  ASSERT_TRUE(r.mesh.findMetadata("source.format"));
  EXPECT_EQ(*r.mesh.findMetadata("source.format"), "plot3d");
}

TEST(Plot3dImport, BluntFinSplitFiveMatchesTableOne) {
  const std::string xyz = dataPath("plot3d/bluntfinxyz.bin"), q = dataPath("plot3d/bluntfinq.bin");
  auto r = importFiles({xyz, q}, 5);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  const MeshStats s = computeMeshStats(r->mesh);
  EXPECT_EQ(s.points, 40960u);
  EXPECT_EQ(s.tets, 187395u);
  EXPECT_EQ(s.faces, 381548u);
  EXPECT_EQ(s.boundary_faces, 13516u);
  EXPECT_EQ(s.non_manifold_faces, 0u);
  EXPECT_EQ(s.inverted, 0u);
  // The blunt fin has collapsed cells: they are kept and reported.
  EXPECT_GT(r->report.zero_volume, 0u);
  EXPECT_EQ(r->report.zero_volume, s.zero_volume);
  EXPECT_EQ(r->report.dropped_cells, 0u);
  EXPECT_EQ(r->report.welded_points, 0u);
  // The Q file's 484 trailing zero bytes are accepted with a warning that counts them.
  ASSERT_EQ(r->report.warnings.size(), 1u);
  EXPECT_NE(r->report.warnings[0].find("484 trailing zero bytes"), std::string::npos) << r->report.warnings[0];
  EXPECT_NE(r->report.warnings[0].find("bluntfinq.bin"), std::string::npos);
  expectBitExact(*r, xyz, q);
  EXPECT_TRUE(r->mesh.checkConsistency("blunt fin").isOk());
  EXPECT_EQ(*r->mesh.findMetadata("plot3d.fsmach"), "2.95000005");
  EXPECT_EQ(*r->mesh.findMetadata("plot3d.re"), "2100000");
}

// The Q file given before its grid: blunt fin's Q file reads as no grid, and is recognised as a Q
// file; the combustion chamber's Q file happens to read as a grid (with IBLANK), and then its grid
// file is recognised as a grid of the same dimensions. Both errors say to give the grid first.
TEST(Plot3dErrors, QFileBeforeItsGridSaysWhichComesFirst) {
  const std::string advice = "give the grid file first, then the Q file (gtn convert GRID.xyz SOLUTION.q -o OUT.gtn)";
  const std::string fin_q = dataPath("plot3d/bluntfinq.bin");
  auto fin = importFiles({fin_q, dataPath("plot3d/bluntfinxyz.bin")});
  ASSERT_FALSE(fin.isOk());
  EXPECT_EQ(fin.status().message(), fin_q +
                                        ": a PLOT3D Q (solution) file (big-endian, no record markers, single grid, "
                                        "float32, grids 40x32x32), not a grid file: " +
                                        advice);
  const std::string comb_q = dataPath("plot3d/combq.bin"), comb_xyz = dataPath("plot3d/combxyz.bin");
  auto comb = importFiles({comb_q, comb_xyz});
  ASSERT_FALSE(comb.isOk());
  EXPECT_EQ(comb.status().message(), comb_xyz +
                                         ": a PLOT3D grid file (big-endian, no record markers, single grid, 3D, "
                                         "float32, no IBLANK, grids 57x33x25), not a Q or function file for the grid " +
                                         comb_q + ", which may be the Q file: " + advice);
}

TEST(Plot3dImport, CombustionChamberBothSplits) {
  const std::string xyz = dataPath("plot3d/combxyz.bin"), q = dataPath("plot3d/combq.bin");
  auto five = importFiles({xyz, q}, 5);
  ASSERT_TRUE(five.isOk()) << five.status().message();
  const MeshStats s5 = computeMeshStats(five->mesh);
  // Two warped cells would give 5 tetrahedra of mixed orientation (flipped, they overlapped their
  // neighbours): each is split around an added point into 12 instead.
  EXPECT_EQ(five->report.steiner_points, 2u);
  EXPECT_EQ(five->report.flipped, 0u);
  EXPECT_EQ(s5.points, 47025u + 2u);
  EXPECT_EQ(s5.tets, 215040u - 2u * 5u + 2u * 12u);
  EXPECT_EQ(s5.boundary_faces, 15616u);
  EXPECT_EQ(s5.non_manifold_faces, 0u);
  EXPECT_EQ(s5.inverted, 0u);
  EXPECT_EQ(five->report.zero_volume, s5.zero_volume);
  ASSERT_EQ(five->report.warnings.size(), 1u);
  EXPECT_NE(five->report.warnings[0].find("2 cells that are not convex split around a point added"), std::string::npos)
      << five->report.warnings[0];
  expectBitExact(*five, xyz, q, 2);
  // Each added point's fields are the mean of its cell's 8 corners.
  const Field* density = five->mesh.findPointField("density");
  for (uint32_t p = 47025; p < 47027; ++p) {
    std::set<uint32_t> corners;
    for (const Tet& t : five->mesh.tets)
      if (std::find(t.begin(), t.end(), p) != t.end()) corners.insert(t.begin(), t.end());
    corners.erase(p);
    ASSERT_EQ(corners.size(), 8u);
    double sum = 0;
    for (uint32_t c : corners) sum += density->get(c, 0);
    EXPECT_EQ(density->get(p, 0), static_cast<double>(static_cast<float>(sum / 8.0)));
  }

  auto six = importFiles({xyz, q}, 6);
  ASSERT_TRUE(six.isOk()) << six.status().message();
  const MeshStats s6 = computeMeshStats(six->mesh);
  EXPECT_EQ(s6.points, 47025u);
  EXPECT_EQ(s6.tets, 56u * 32u * 24u * 6u);
  EXPECT_EQ(s6.boundary_faces, 15616u);
  EXPECT_EQ(s6.non_manifold_faces, 0u);
  EXPECT_EQ(s6.inverted, 0u);
  EXPECT_EQ(six->report.zero_volume, s6.zero_volume);
  // Each split closes up: its tetrahedra add up to the volume its boundary encloses (divergence
  // theorem). (The two splits differ by a little: they cut the curved cell faces along other
  // diagonals. The two warped cells' inverted slivers were too thin to show here; flipped == 0 is
  // what shows they are gone.)
  for (const ImportResult* r : {&*five, &*six}) {
    double enclosed = 0;
    const double origin[3] = {0, 0, 0};
    for (const Triangle& t : boundaryTriangles(r->mesh, computeFaceAdjacency(r->mesh)))
      enclosed += signedVolume(origin, r->mesh.point(t[0]), r->mesh.point(t[1]), r->mesh.point(t[2]));
    EXPECT_NEAR(computeMeshStats(r->mesh).total_volume, enclosed, 1e-9 * enclosed);
  }
  // The Q header is all zero: the metadata says so rather than being left out.
  EXPECT_EQ(*six->mesh.findMetadata("plot3d.fsmach"), "0");
}

TEST(Plot3dImport, BluntFinSplitSixIsConforming) {
  auto r = importFiles({dataPath("plot3d/bluntfinxyz.bin")}, 6);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  const MeshStats s = computeMeshStats(r->mesh);
  EXPECT_EQ(s.tets, 39u * 31u * 31u * 6u);
  EXPECT_EQ(s.boundary_faces, 13516u);
  EXPECT_EQ(s.non_manifold_faces, 0u);
  EXPECT_EQ(s.inverted, 0u);
  EXPECT_TRUE(r->mesh.point_fields.empty());
}

// ---- Synthetic files ----------------------------------------------------------------------------

struct Bytes {
  bool big_endian = true;
  std::string s;
  void put(uint64_t v, int size) {
    for (int i = 0; i < size; ++i) {
      const int shift = 8 * (big_endian ? size - 1 - i : i);
      s.push_back(static_cast<char>((v >> shift) & 0xFF));
    }
  }
  void i32(int32_t v) { put(static_cast<uint32_t>(v), 4); }
  void real(double v, int precision) {
    if (precision == 4) {
      put(std::bit_cast<uint32_t>(static_cast<float>(v)), 4);
    } else {
      put(std::bit_cast<uint64_t>(v), 8);
    }
  }
};

// A file of records, with Fortran record markers when `marker` is 4 or 8.
struct RecordWriter {
  bool big_endian = true;
  int marker = 0;
  std::string out;
  void record(const std::string& payload) {
    Bytes m{big_endian, ""};
    if (marker) m.put(payload.size(), marker);
    out += m.s + payload + m.s;
  }
  // One record split into subrecords of at most `chunk` bytes (negative leading markers on all but
  // the last, negative trailing markers on all but the first: gfortran's scheme).
  void subrecords(const std::string& payload, size_t chunk) {
    for (size_t at = 0; at < payload.size(); at += chunk) {
      const size_t len = std::min(chunk, payload.size() - at);
      const bool more = at + len<payload.size(), continued = at> 0;
      Bytes head{big_endian, ""}, tail{big_endian, ""};
      head.i32(more ? -static_cast<int32_t>(len) : static_cast<int32_t>(len));
      tail.i32(continued ? -static_cast<int32_t>(len) : static_cast<int32_t>(len));
      out += head.s + payload.substr(at, len) + tail.s;
    }
  }
};

struct Block {
  int n[3];
  std::vector<double> x, y, z;
  std::vector<int32_t> iblank;
  size_t points() const { return static_cast<size_t>(n[0]) * n[1] * n[2]; }
};

// A right-handed sheared box grid starting at x = `origin`.
Block boxBlock(int ni, int nj, int nk, double origin = 0.0) {
  Block b{{ni, nj, nk}, {}, {}, {}, {}};
  for (int k = 0; k < nk; ++k)
    for (int j = 0; j < nj; ++j)
      for (int i = 0; i < ni; ++i) {
        b.x.push_back(origin + i + 0.125 * j);
        b.y.push_back(j + 0.25 * k);
        b.z.push_back(k + 0.0625 * (origin + i));
      }
  return b;
}

struct GridOptions {
  bool big_endian = true;
  int marker = 0;
  bool multi = false;
  int precision = 4;
  bool iblank = false;
  size_t subrecord_chunk = 0;  // > 0: write data records as subrecords of this size
  bool planes = false;         // grid and Q files plane by plane (PLOT3D's /PLANES): a record per k-plane
  bool per_variable = false;   // grid and Q files a record per variable (X, Y, Z, IBLANK; each Q variable)
};

// Multi-grid with IBLANK and `marker`-byte record markers: float32 with 4-byte markers, float64 with 8.
GridOptions markedMultiGrid(int marker, bool big_endian) {
  GridOptions o;
  o.big_endian = big_endian;
  o.marker = marker;
  o.multi = true;
  o.precision = marker == 4 ? 4 : 8;
  o.iblank = true;
  return o;
}

// Writes the grid count record (multi-grid files) and leaves in b the dimensions of every grid, each
// followed by `per_grid` when it is given (function files: the variable count); the caller may add
// more and ends the record.
void beginDims(RecordWriter& w, Bytes& b, const std::vector<Block>& blocks, const GridOptions& o, int per_grid = -1) {
  b.s.clear();
  if (o.multi) {
    b.i32(static_cast<int32_t>(blocks.size()));
    w.record(b.s);
  }
  b.s.clear();
  for (const Block& g : blocks) {
    for (int a = 0; a < 3; ++a) b.i32(g.n[a]);
    if (per_grid >= 0) b.i32(per_grid);
  }
}

std::string gridFile(const std::vector<Block>& blocks, const GridOptions& o) {
  RecordWriter w{o.big_endian, o.marker, ""};
  Bytes b{o.big_endian, ""};
  beginDims(w, b, blocks, o);
  w.record(b.s);
  for (const Block& g : blocks) {
    // One record for the grid, or one per k-plane holding that plane's X, Y, Z (and IBLANK) values,
    // or one per variable.
    const size_t n = g.points(), span = o.planes ? static_cast<size_t>(g.n[0]) * g.n[1] : n;
    if (o.per_variable) {
      for (const auto* v : {&g.x, &g.y, &g.z}) {
        b.s.clear();
        for (size_t p = 0; p < n; ++p) b.real((*v)[p], o.precision);
        w.record(b.s);
      }
      if (o.iblank) {
        b.s.clear();
        for (size_t p = 0; p < n; ++p) b.i32(g.iblank[p]);
        w.record(b.s);
      }
      continue;
    }
    for (size_t first = 0; first < n; first += span) {
      b.s.clear();
      for (const auto* v : {&g.x, &g.y, &g.z})
        for (size_t p = first; p < first + span; ++p) b.real((*v)[p], o.precision);
      if (o.iblank)
        for (size_t p = first; p < first + span; ++p) b.i32(g.iblank[p]);
      if (o.subrecord_chunk) {
        w.subrecords(b.s, o.subrecord_chunk);
      } else {
        w.record(b.s);
      }
    }
  }
  return w.out;
}

// Q file with density = 1 + p/1000, momentum (p, -p, 2p), energy 3 + p for point p of each block.
std::string qFile(const std::vector<Block>& blocks, const GridOptions& o) {
  RecordWriter w{o.big_endian, o.marker, ""};
  Bytes b{o.big_endian, ""};
  beginDims(w, b, blocks, o);
  w.record(b.s);
  for (size_t gi = 0; gi < blocks.size(); ++gi) {
    const Block& g = blocks[gi];
    b.s.clear();
    for (double v : {0.75, 2.5, 1.0e6, 0.125 + static_cast<double>(gi)}) b.real(v, o.precision);
    w.record(b.s);
    // The five variables in one record, or in one record per k-plane, or one record each.
    const size_t n = g.points(), span = o.planes ? static_cast<size_t>(g.n[0]) * g.n[1] : n;
    for (size_t first = 0; first < n; first += span) {
      b.s.clear();
      for (int var = 0; var < 5; ++var) {
        for (size_t p = first; p < first + span; ++p) {
          const double d = static_cast<double>(p);
          const double values[5] = {1 + d / 1000, d, -d, 2 * d, 3 + d};
          b.real(values[var], o.precision);
        }
        if (o.per_variable) {
          w.record(b.s);
          b.s.clear();
        }
      }
      if (!o.per_variable) w.record(b.s);
    }
  }
  return w.out;
}

// OVERFLOW Q file: NQ and NQC after the dimensions of all grids; per grid a freestream record of
// FSMACH ALPHA REY TIME GAMINF BETA TINF, IGAM (int32), HTINF HT1 HT2, RGAS(1:max(2,NQC)), FSMFR TVREF
// DTVREF, then NQ variables: q1 .. q5 as in qFile, q(6+k) = 10 * (k + 1) + p.
std::string overflowQFile(const std::vector<Block>& blocks, const GridOptions& o, int nq, int nqc) {
  RecordWriter w{o.big_endian, o.marker, ""};
  Bytes b{o.big_endian, ""};
  beginDims(w, b, blocks, o);
  b.i32(nq);
  b.i32(nqc);
  w.record(b.s);
  for (size_t gi = 0; gi < blocks.size(); ++gi) {
    const Block& g = blocks[gi];
    b.s.clear();
    for (double v : {0.75, 2.5, 1.0e6, 0.125, 1.375, 0.5, 518.5}) b.real(v, o.precision);
    b.i32(1);  // IGAM
    for (double v : {0.0, 0.0, 0.0}) b.real(v, o.precision);
    for (int k = 0; k < std::max(2, nqc); ++k) b.real(1716.0 + k, o.precision);
    for (double v : {0.0, 1.0, 0.0}) b.real(v, o.precision);
    w.record(b.s);
    b.s.clear();
    const size_t n = g.points();
    for (int var = 0; var < nq; ++var)
      for (size_t p = 0; p < n; ++p) {
        const double d = static_cast<double>(p);
        const double values[5] = {1 + d / 1000, d, -d, 2 * d, 3 + d};
        b.real(var < 5 ? values[var] : 10.0 * (var - 4) + d, o.precision);
      }
    w.record(b.s);
  }
  return w.out;
}

// Function file with `nvar` variables: value v * 100 + p.
std::string functionFile(const std::vector<Block>& blocks, const GridOptions& o, int nvar) {
  RecordWriter w{o.big_endian, o.marker, ""};
  Bytes b{o.big_endian, ""};
  beginDims(w, b, blocks, o, nvar);
  w.record(b.s);
  for (const Block& g : blocks) {
    b.s.clear();
    for (int v = 0; v < nvar; ++v)
      for (size_t p = 0; p < g.points(); ++p) b.real(v * 100.0 + static_cast<double>(p), o.precision);
    w.record(b.s);
  }
  return w.out;
}

class Plot3dSynthetic : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::tempDir(std::string("plot3d-") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  std::string write(const std::string& name, const std::string& bytes) {
    const std::string p = dir_ + "/" + name;
    test::writeFile(p, bytes);
    return p;
  }
  std::string dir_;
};

// Coordinates of the imported mesh equal the blocks' (converted to the file's precision).
void expectCoords(const TetMesh& mesh, const std::vector<Block>& blocks, int precision) {
  size_t base = 0, mismatch = 0;
  for (const Block& g : blocks) {
    for (size_t p = 0; p < g.points(); ++p) {
      const double want[3] = {g.x[p], g.y[p], g.z[p]};
      for (int a = 0; a < 3; ++a) {
        const double w = precision == 4 ? static_cast<double>(static_cast<float>(want[a])) : want[a];
        mismatch += std::bit_cast<uint64_t>(mesh.coords[3 * (base + p) + a]) != std::bit_cast<uint64_t>(w);
      }
    }
    base += g.points();
  }
  EXPECT_EQ(base, mesh.numPoints());
  EXPECT_EQ(mismatch, 0u);
}

TEST_F(Plot3dSynthetic, LittleEndianWithFourByteMarkers) {
  const std::vector<Block> blocks = {boxBlock(4, 3, 5)};
  GridOptions o;
  o.big_endian = false;
  o.marker = 4;
  const std::string xyz = write("le4.xyz", gridFile(blocks, o));
  const std::string q = write("le4.q", qFile(blocks, o));
  auto r = importFiles({xyz, q}, 6);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.coord_type, ScalarType::kFloat32);
  EXPECT_EQ(r->mesh.numTets(), 3u * 2u * 4u * 6u);
  expectCoords(r->mesh, blocks, 4);
  const Field* density = r->mesh.findPointField("density");
  const Field* momentum = r->mesh.findPointField("momentum");
  ASSERT_TRUE(density && momentum);
  EXPECT_EQ(density->get(7, 0), static_cast<double>(static_cast<float>(1 + 7.0 / 1000)));
  EXPECT_EQ(momentum->get(7, 0), 7.0);
  EXPECT_EQ(momentum->get(7, 1), -7.0);
  EXPECT_EQ(momentum->get(7, 2), 14.0);
  EXPECT_EQ(r->mesh.findPointField("stagnation_energy")->get(59, 0), 62.0);
  EXPECT_EQ(*r->mesh.findMetadata("plot3d.fsmach"), "0.75");
  EXPECT_EQ(*r->mesh.findMetadata("plot3d.alpha"), "2.5");
  EXPECT_EQ(*r->mesh.findMetadata("plot3d.re"), "1000000");
  EXPECT_EQ(*r->mesh.findMetadata("plot3d.time"), "0.125");
  const MeshStats s = computeMeshStats(r->mesh);
  EXPECT_EQ(s.inverted, 0u);
  EXPECT_EQ(s.zero_volume, 0u);
  EXPECT_EQ(s.non_manifold_faces, 0u);
}

TEST_F(Plot3dSynthetic, MultiGridFloat64WithEightByteMarkers) {
  // The second block touches the first along x = 3: blocks are not joined, so both keep their faces.
  const std::vector<Block> blocks = {boxBlock(4, 3, 3), boxBlock(3, 3, 3, 3.0)};
  GridOptions o;
  o.marker = 8;
  o.multi = true;
  o.precision = 8;
  const std::string xyz = write("m8.xyz", gridFile(blocks, o));
  const std::string q = write("m8.q", qFile(blocks, o));
  auto r = importFiles({xyz, q}, 5);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.coord_type, ScalarType::kFloat64);
  EXPECT_EQ(r->mesh.numPoints(), 36u + 27u);
  EXPECT_EQ(r->mesh.numTets(), (3u * 2u * 2u + 2u * 2u * 2u) * 5u);
  expectCoords(r->mesh, blocks, 8);
  const Field* density = r->mesh.findPointField("density");
  ASSERT_TRUE(density);
  EXPECT_EQ(density->type, ScalarType::kFloat64);
  // Point 0 of the second block follows the 36 points of the first.
  EXPECT_EQ(density->get(36, 0), 1.0);
  EXPECT_EQ(density->get(35, 0), 1 + 35.0 / 1000);
  EXPECT_EQ(*r->mesh.findMetadata("plot3d.grids"), "2");
  EXPECT_EQ(*r->mesh.findMetadata("plot3d.re"), "1000000");
  // The per-grid headers differ in time: the metadata keeps grid 1's and a warning says so.
  EXPECT_EQ(*r->mesh.findMetadata("plot3d.time"), "0.125");
  ASSERT_EQ(r->report.warnings.size(), 1u);
  const MeshStats s = computeMeshStats(r->mesh);
  EXPECT_EQ(s.coincident_points, 9u);
  EXPECT_EQ(s.inverted, 0u);
  EXPECT_EQ(s.non_manifold_faces, 0u);
  // Each block is a closed box of its own: 2 triangles per boundary quad.
  EXPECT_EQ(s.boundary_faces, 2u * 2u * (3 * 2 + 3 * 2 + 2 * 2) + 2u * 2u * (2 * 2 * 3));
  EXPECT_TRUE(r->mesh.checkConsistency("multi-grid").isOk());

  // --weld joins the blocks at their 9 shared points (the split 6 diagonals agree there) and
  // collapses nothing.
  auto welded = importFiles({xyz, q}, 6, true);
  ASSERT_TRUE(welded.isOk()) << welded.status().message();
  EXPECT_EQ(welded->report.welded_points, 9u);
  EXPECT_EQ(welded->report.collapsed_tets, 0u);
  const MeshStats ws = computeMeshStats(welded->mesh);
  EXPECT_EQ(ws.points, 36u + 27u - 9u);
  EXPECT_EQ(ws.coincident_points, 0u);
  EXPECT_EQ(ws.non_manifold_faces, 0u);
  EXPECT_EQ(ws.boundary_faces, 2u * (2 * (5 * 2 + 5 * 2 + 2 * 2)));
  EXPECT_EQ(welded->mesh.findPointField("density")->itemCount(), ws.points);
}

std::string qName(int k) {
  std::string name = std::to_string(k);
  name.insert(name.begin(), 'q');
  return name;
}

// OVERFLOW's Q layout (VTK's multi-bin-oflow.q is one): classic names for the first five variables,
// q6 .. qNQ for the rest, GAMINF BETA TINF in the metadata; with and without record markers, where
// only the exact size of the longer freestream record tells the layout.
TEST_F(Plot3dSynthetic, OverflowQFile) {
  const std::vector<Block> blocks = {boxBlock(4, 3, 3), boxBlock(3, 3, 3, 3.0)};
  for (int marker : {4, 0}) {
    for (int nqc : {0, 3}) {
      GridOptions o;
      o.big_endian = false;
      o.marker = marker;
      o.multi = true;
      o.precision = 8;
      const std::string tag = std::to_string(marker) + "-" + std::to_string(nqc);
      const std::string xyz = write("of" + tag + ".xyz", gridFile(blocks, o));
      const std::string q = write("of" + tag + ".q", overflowQFile(blocks, o, 7 + nqc, nqc));
      auto r = importFiles({xyz, q}, 6);
      ASSERT_TRUE(r.isOk()) << tag << ": " << r.status().message();
      const TetMesh& m = r->mesh;
      EXPECT_EQ(m.numPoints(), 36u + 27u);
      const Field* density = m.findPointField("density");
      const Field* momentum = m.findPointField("momentum");
      const Field* energy = m.findPointField("stagnation_energy");
      ASSERT_TRUE(density && momentum && energy) << tag;
      EXPECT_EQ(density->get(35, 0), 1 + 35.0 / 1000);
      EXPECT_EQ(density->get(36, 0), 1.0);  // point 0 of the second grid
      EXPECT_EQ(momentum->get(7, 2), 14.0);
      EXPECT_EQ(energy->get(40, 0), 7.0);
      for (int k = 6; k <= 7 + nqc; ++k) {
        const Field* f = m.findPointField(qName(k));
        ASSERT_TRUE(f) << tag << " q" << k;
        EXPECT_EQ(f->type, ScalarType::kFloat64);
        EXPECT_EQ(f->get(5, 0), 10.0 * (k - 5) + 5) << tag << " q" << k;
        EXPECT_EQ(f->get(36 + 2, 0), 10.0 * (k - 5) + 2) << tag << " q" << k;
      }
      EXPECT_EQ(m.findPointField(qName(8 + nqc)), nullptr);
      EXPECT_EQ(m.findPointField("q5"), nullptr);
      EXPECT_EQ(*m.findMetadata("plot3d.fsmach"), "0.75");
      EXPECT_EQ(*m.findMetadata("plot3d.time"), "0.125");
      EXPECT_EQ(*m.findMetadata("plot3d.gaminf"), "1.375");
      EXPECT_EQ(*m.findMetadata("plot3d.tinf"), "518.5");
      EXPECT_EQ(*m.findMetadata("plot3d.nq"), std::to_string(7 + nqc));
      EXPECT_EQ(*m.findMetadata("plot3d.nqc"), std::to_string(nqc));
      EXPECT_TRUE(r->report.warnings.empty()) << r->report.warnings[0];
    }
  }
  // A truncated OVERFLOW file fails naming the file (its bytes fit no layout).
  GridOptions o;
  o.big_endian = false;
  o.marker = 4;
  o.multi = true;
  o.precision = 8;
  const std::string xyz = write("cut.xyz", gridFile(blocks, o));
  const std::string full = overflowQFile(blocks, o, 6, 0);
  const std::string q = write("cut.q", full.substr(0, full.size() - 12));
  auto r = importFiles({xyz, q}, 6);
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().message().rfind(q + ": ", 0), 0u) << r.status().message();
  EXPECT_NE(r.status().message().find("OVERFLOW"), std::string::npos) << r.status().message();
}

// Files written plane by plane are told from whole files by their record markers and read with the
// same values; a grid of one k-plane is the same either way and is not reported as ambiguous.
TEST_F(Plot3dSynthetic, PlanesLayoutWithRecordMarkers) {
  std::vector<Block> blocks = {boxBlock(4, 3, 5), boxBlock(3, 3, 2, 3.0)};
  for (Block& g : blocks) g.iblank.assign(g.points(), 1);
  blocks[0].iblank[0] = 0;  // one hole: the cell at the origin goes
  for (int marker : {4, 8}) {
    const GridOptions o = markedMultiGrid(marker, marker == 4);
    const std::string tag = std::to_string(marker);
    GridOptions po = o;
    po.planes = true;
    const std::string xyz = write("planes" + tag + ".xyz", gridFile(blocks, po));
    const std::string q = write("planes" + tag + ".q", qFile(blocks, po));
    auto r = importFiles({xyz, q}, 6);
    ASSERT_TRUE(r.isOk()) << tag << ": " << r.status().message();
    const TetMesh& m = r->mesh;
    expectCoords(m, blocks, o.precision);
    EXPECT_EQ(m.numTets(), (3u * 2u * 4u - 1u + 2u * 2u * 1u) * 6u);
    EXPECT_NE(m.findMetadata("plot3d.layout")->find(", planes"), std::string::npos) << *m.findMetadata("plot3d.layout");
    const Field* density = m.findPointField("density");
    const Field* momentum = m.findPointField("momentum");
    const Field* iblank = m.findPointField("iblank");
    ASSERT_TRUE(density && momentum && iblank);
    // Point 37 of the first grid lies in its fourth k-plane (12 points a plane).
    EXPECT_EQ(density->get(37, 0),
              static_cast<double>(o.precision == 4 ? static_cast<float>(1 + 37.0 / 1000) : 1 + 37.0 / 1000));
    EXPECT_EQ(momentum->get(37, 2), 74.0);
    EXPECT_EQ(m.findPointField("stagnation_energy")->get(60 + 10, 0), 13.0);  // point 10 of the second grid
    EXPECT_EQ(iblank->get(0, 0), 0);
    EXPECT_EQ(iblank->get(1, 0), 1);
    // The same mesh as the whole layout gives.
    const std::string wxyz = write("whole" + tag + ".xyz", gridFile(blocks, o));
    const std::string wq = write("whole" + tag + ".q", qFile(blocks, o));
    auto w = importFiles({wxyz, wq}, 6);
    ASSERT_TRUE(w.isOk()) << w.status().message();
    EXPECT_EQ(w->mesh.coords, m.coords);
    EXPECT_EQ(w->mesh.tets, m.tets);
    EXPECT_EQ(w->mesh.findPointField("momentum")->bytes, momentum->bytes);
    EXPECT_EQ(w->mesh.findMetadata("plot3d.layout")->find(", planes"), std::string::npos);
  }
  // Single k-plane grids: whole and planes are one layout, read without an ambiguity error.
  const std::vector<Block> flat = {boxBlock(3, 3, 1)};
  GridOptions o;
  o.marker = 4;
  o.planes = true;
  auto r = importFiles({write("flat.xyz", gridFile(flat, o))}, 6);
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().message().find("ambiguous"), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find("a dimension below 2"), std::string::npos) << r.status().message();
}

// Fortran's `write(u) x` / `write(u) y` / ...: a record per variable, in grid and Q files, read with
// the values of the whole layout. A grid of three k-planes has records of the same sizes either way
// (three planes of X, Y and Z, or X, Y and Z of three planes): the reading whose cells are consistent
// wins, both ways round; a Q file of five k-planes likewise follows its grid's records.
TEST_F(Plot3dSynthetic, OneRecordPerVariable) {
  std::vector<Block> blocks = {boxBlock(4, 3, 5), boxBlock(3, 3, 2, 3.0)};
  for (Block& g : blocks) g.iblank.assign(g.points(), 1);
  blocks[0].iblank[0] = 0;
  for (int marker : {4, 8}) {
    const GridOptions o = markedMultiGrid(marker, marker == 8);
    const std::string tag = std::to_string(marker);
    GridOptions vo = o;
    vo.per_variable = true;
    auto v = importFiles(
        {write("var" + tag + ".xyz", gridFile(blocks, vo)), write("var" + tag + ".q", qFile(blocks, vo))}, 6);
    ASSERT_TRUE(v.isOk()) << tag << ": " << v.status().message();
    auto w = importFiles(
        {write("whole" + tag + ".xyz", gridFile(blocks, o)), write("whole" + tag + ".q", qFile(blocks, o))}, 6);
    ASSERT_TRUE(w.isOk()) << w.status().message();
    expectCoords(v->mesh, blocks, o.precision);
    EXPECT_EQ(v->mesh.coords, w->mesh.coords);
    EXPECT_EQ(v->mesh.tets, w->mesh.tets);
    for (const char* f : {"density", "momentum", "stagnation_energy", "iblank"})
      EXPECT_EQ(v->mesh.findPointField(f)->bytes, w->mesh.findPointField(f)->bytes) << f;
    EXPECT_NE(v->mesh.findMetadata("plot3d.layout")->find(", one record per variable"), std::string::npos)
        << *v->mesh.findMetadata("plot3d.layout");
  }
  for (int nk : {3, 5}) {
    const std::vector<Block> g = {boxBlock(4, 3, nk)};
    GridOptions o;
    o.big_endian = false;
    o.marker = 4;
    for (int mode = 0; mode < 2; ++mode) {
      GridOptions m = o;
      (mode == 0 ? m.planes : m.per_variable) = true;
      const std::string name = "nk" + std::to_string(nk) + (mode == 0 ? "planes" : "vars");
      auto r = importFiles({write(name + ".xyz", gridFile(g, m)), write(name + ".q", qFile(g, m))}, 6);
      ASSERT_TRUE(r.isOk()) << name << ": " << r.status().message();
      expectCoords(r->mesh, g, 4);
      EXPECT_EQ(r->mesh.findPointField("momentum")->get(13, 2), 26.0) << name;
      EXPECT_NE(r->mesh.findMetadata("plot3d.layout")->find(mode == 0 ? ", planes" : ", one record per variable"),
                std::string::npos)
          << name;
      EXPECT_EQ(computeMeshStats(r->mesh).zero_volume, 0u) << name;
    }
  }
}

// A grid and its Q file whose records are cut differently (planes and one record per variable) where
// their sizes coincide (5 k-planes, 5 Q variables): the data decides each file's reading, not the
// grid's choice. A .p3d key "records" can name it; a wrong one says what it restricted.
TEST_F(Plot3dSynthetic, GridAndQFileCutDifferently) {
  const std::vector<Block> g = {boxBlock(4, 3, 5)};
  GridOptions planes, vars;
  planes.marker = vars.marker = 4;
  planes.planes = true;
  vars.per_variable = true;
  for (int mode = 0; mode < 2; ++mode) {
    const GridOptions& go = mode == 0 ? planes : vars;
    const GridOptions& qo = mode == 0 ? vars : planes;
    const std::string name = mode == 0 ? "gp_qv" : "gv_qp";
    auto r = importFiles({write(name + ".xyz", gridFile(g, go)), write(name + ".q", qFile(g, qo))}, 6);
    ASSERT_TRUE(r.isOk()) << name << ": " << r.status().message();
    expectCoords(r->mesh, g, 4);
    const Field* density = r->mesh.findPointField("density");
    const Field* momentum = r->mesh.findPointField("momentum");
    for (size_t p : {size_t{0}, size_t{13}, size_t{59}}) {
      EXPECT_EQ(density->get(p, 0), static_cast<double>(static_cast<float>(1 + p / 1000.0))) << name << " " << p;
      EXPECT_EQ(momentum->get(p, 2), 2.0 * p) << name << " " << p;
    }
  }
  // Three k-planes: the grid's own records settle it, in either direction, and a .p3d may say so.
  const std::vector<Block> three = {boxBlock(4, 3, 3)};
  write("three.xyz", gridFile(three, vars));
  write("three.p3d", R"({"records": "variables", "filenames": [{"xyz": "three.xyz"}]})");
  auto named = importFiles({dir_ + "/three.p3d"});
  ASSERT_TRUE(named.isOk()) << named.status().message();
  expectCoords(named->mesh, three, 4);
  write("wrong.p3d", R"({"records": "whole", "byte-order": "big", "filenames": [{"xyz": "three.xyz"}]})");
  auto wrong = importFiles({dir_ + "/wrong.p3d"});
  ASSERT_FALSE(wrong.isOk());
  EXPECT_NE(wrong.status().message().find("only readings that the meta-file " + dir_ +
                                          "/wrong.p3d allows were tried (big-endian)"),
            std::string::npos)
      << wrong.status().message();
  write("bad.p3d", R"({"records": "rows", "filenames": [{"xyz": "three.xyz"}]})");
  auto bad = importFiles({dir_ + "/bad.p3d"});
  ASSERT_FALSE(bad.isOk());
  EXPECT_NE(bad.status().message().find("\"records\" must be"), std::string::npos) << bad.status().message();
}

// Without record markers (C, or Fortran's access='stream') a file written plane by plane has the size
// of a whole one: the grid is read plane by plane only because its cells come out consistent that way,
// its Q file as its values say; a whole file (blunt fin's layout) stays whole.
TEST_F(Plot3dSynthetic, PlanesWithoutRecordMarkers) {
  std::vector<Block> blocks = {boxBlock(4, 3, 5), boxBlock(3, 3, 2, 3.0)};
  for (Block& g : blocks) g.iblank.assign(g.points(), 1);
  for (int iblank = 0; iblank < 2; ++iblank) {
    GridOptions o;
    o.big_endian = iblank == 0;
    o.multi = true;
    o.precision = iblank ? 8 : 4;
    o.iblank = iblank != 0;
    GridOptions po = o;
    po.planes = true;
    const std::string tag = std::to_string(iblank);
    auto p =
        importFiles({write("sp" + tag + ".xyz", gridFile(blocks, po)), write("sp" + tag + ".q", qFile(blocks, po))}, 6);
    ASSERT_TRUE(p.isOk()) << p.status().message();
    expectCoords(p->mesh, blocks, o.precision);
    EXPECT_NE(p->mesh.findMetadata("plot3d.layout")->find("no record markers"), std::string::npos);
    EXPECT_NE(p->mesh.findMetadata("plot3d.layout")->find(", planes"), std::string::npos);
    EXPECT_EQ(p->mesh.findPointField("momentum")->get(37, 2), 74.0);
    EXPECT_EQ(p->report.flipped, 0u);
    auto w =
        importFiles({write("sw" + tag + ".xyz", gridFile(blocks, o)), write("sw" + tag + ".q", qFile(blocks, o))}, 6);
    ASSERT_TRUE(w.isOk()) << w.status().message();
    EXPECT_EQ(w->mesh.findMetadata("plot3d.layout")->find(", planes"), std::string::npos);
    EXPECT_EQ(w->mesh.coords, p->mesh.coords);
    EXPECT_EQ(w->mesh.findPointField("momentum")->bytes, p->mesh.findPointField("momentum")->bytes);
  }
}

// Multi-grid files as some codes write them: each grid's dimensions in a record of its own, and a
// block without cells (a dimension of 1), which is kept as points no tetrahedron uses.
TEST_F(Plot3dSynthetic, DimensionsPerGridAndFlatBlocks) {
  const std::vector<Block> blocks = {boxBlock(3, 3, 3), boxBlock(4, 3, 1, 5.0), boxBlock(2, 3, 2, 9.0)};
  RecordWriter w{false, 4, ""};
  Bytes b{false, ""};
  b.i32(3);
  w.record(b.s);
  for (const Block& g : blocks) {
    b.s.clear();
    for (int a = 0; a < 3; ++a) b.i32(g.n[a]);
    w.record(b.s);
  }
  for (const Block& g : blocks) {
    b.s.clear();
    for (const auto* v : {&g.x, &g.y, &g.z})
      for (double x : *v) b.real(x, 4);
    w.record(b.s);
  }
  auto r = importFiles({write("pergrid.xyz", w.out)}, 6);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  expectCoords(r->mesh, blocks, 4);
  EXPECT_EQ(r->mesh.numTets(), (8u + 2u) * 6u);
  EXPECT_NE(r->mesh.findMetadata("plot3d.layout")->find(", dimensions per grid"), std::string::npos);
  ASSERT_EQ(r->report.warnings.size(), 1u);
  EXPECT_NE(r->report.warnings[0].find("grid 2 is 4x3x1: a dimension below 2, so it has no cells; its 12 points stay"),
            std::string::npos)
      << r->report.warnings[0];
  EXPECT_EQ(computeMeshStats(r->mesh).unreferenced_points, 12u);
  // Only flat blocks: nothing to convert.
  GridOptions o;
  o.marker = 4;
  o.multi = true;
  auto flat = importFiles({write("flat2.xyz", gridFile({boxBlock(3, 3, 1), boxBlock(1, 3, 3)}, o))}, 6);
  ASSERT_FALSE(flat.isOk());
  EXPECT_NE(flat.status().message().find("grid 1 is 3x3x1: a dimension below 2"), std::string::npos)
      << flat.status().message();
  EXPECT_NE(flat.status().message().find("(and so are the other 1 grids)"), std::string::npos)
      << flat.status().message();
}

// Fortran compiled with 64-bit default integers (gfortran -fdefault-integer-8) writes the grid count,
// dimensions and IBLANK as 8-byte integers: read with record markers. An ASCII field that overflowed
// its Fortran format is named as such.
TEST_F(Plot3dSynthetic, SixtyFourBitIntegersAndOverflowedFields) {
  std::vector<Block> blocks = {boxBlock(3, 3, 2), boxBlock(2, 3, 3, 4.0)};
  for (Block& g : blocks) g.iblank.assign(g.points(), 1);
  blocks[1].iblank[0] = 0;
  RecordWriter w{true, 4, ""};
  Bytes b{true, ""};
  b.put(2, 8);
  w.record(b.s);
  b.s.clear();
  for (const Block& g : blocks)
    for (int a = 0; a < 3; ++a) b.put(static_cast<uint64_t>(g.n[a]), 8);
  w.record(b.s);
  for (const Block& g : blocks) {
    b.s.clear();
    for (const auto* v : {&g.x, &g.y, &g.z})
      for (double x : *v) b.real(x, 8);
    for (int32_t ib : g.iblank) b.put(static_cast<uint64_t>(static_cast<int64_t>(ib)), 8);
    w.record(b.s);
  }
  auto r = importFiles({write("i8.xyz", w.out)}, 6);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  expectCoords(r->mesh, blocks, 8);
  EXPECT_NE(r->mesh.findMetadata("plot3d.layout")->find("IBLANK, 64-bit integers"), std::string::npos)
      << *r->mesh.findMetadata("plot3d.layout");
  EXPECT_EQ(r->mesh.findPointField("iblank")->get(18, 0), 0);
  EXPECT_EQ(r->mesh.findPointField("iblank")->get(19, 0), 1);
  EXPECT_EQ(r->mesh.numTets(), (2u * 2u * 1u + 1u * 2u * 2u - 1u) * 6u);
  write("ovf.xyz", "3 3 2\n" + std::string("0.0 ") + "**********\n");
  auto a = importFiles({dir_ + "/ovf.xyz"}, 6);
  ASSERT_FALSE(a.isOk());
  EXPECT_NE(
      a.status().message().find("ovf.xyz:2: ASCII PLOT3D: '**********' is a Fortran field that overflowed its format"),
      std::string::npos)
      << a.status().message();
}

TEST_F(Plot3dSynthetic, SubrecordsWithNegativeMarkers) {
  const std::vector<Block> blocks = {boxBlock(3, 3, 3)};
  GridOptions o;
  o.marker = 4;
  o.subrecord_chunk = 100;  // the 324-byte data record as subrecords of 100, 100, 100, 24
  const std::string xyz = write("sub.xyz", gridFile(blocks, o));
  auto r = importFiles({xyz}, 6);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  expectCoords(r->mesh, blocks, 4);
  EXPECT_EQ(r->mesh.numTets(), 48u);
}

// A 3x4x5 float64 grid with IBLANK, plane by plane with 4-byte markers, is exactly as long as a
// marker-less float32 grid of 12x3x4: the reading whose record markers all check out is taken.
TEST_F(Plot3dSynthetic, RecordMarkersOutweighASizeThatMerelyAddsUp) {
  GridOptions o;
  o.big_endian = false;
  o.marker = 4;
  o.precision = 8;
  o.iblank = true;
  o.planes = true;
  std::vector<Block> blocks = {boxBlock(3, 4, 5)};
  blocks[0].iblank.assign(60, 1);
  const std::string bytes = gridFile(blocks, o);
  ASSERT_EQ(bytes.size(), 12u + 4u * 12u * 3u * 4u * 3u);  // the marker-less float32 12x3x4 size
  auto r = importFiles({write("coincidence.xyz", bytes)}, 6);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.numPoints(), 60u);
  EXPECT_EQ(r->mesh.numTets(), 144u);
  expectCoords(r->mesh, blocks, 8);
}

TEST_F(Plot3dSynthetic, AFullyBlankedGridSaysNoTetrahedraAreLeft) {
  std::vector<Block> blocks = {boxBlock(3, 3, 3)};
  blocks[0].iblank.assign(27, 0);
  GridOptions o;
  o.iblank = true;
  auto r = importFiles({write("blank.xyz", gridFile(blocks, o))}, 6);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->mesh.numTets(), 0u);
  EXPECT_EQ(r->report.dropped_cells, 8u);
  ASSERT_FALSE(r->report.warnings.empty());
  EXPECT_EQ(r->report.warnings.back(), "the mesh has no tetrahedra left: all 8 cells were dropped (IBLANK holes)");
}

TEST_F(Plot3dSynthetic, IblankHolesDropCellsAndKeepTheField) {
  std::vector<Block> blocks = {boxBlock(4, 4, 4)};
  blocks[0].iblank.assign(64, 1);
  blocks[0].iblank[1 + 4 * (1 + 4 * 1)] = 0;   // interior hole point (1,1,1): its 8 cells go
  blocks[0].iblank[3 + 4 * (3 + 4 * 3)] = 0;   // corner hole (3,3,3): 1 more cell
  blocks[0].iblank[2 + 4 * (0 + 4 * 0)] = -1;  // fringe point: kept
  blocks[0].iblank[0 + 4 * (3 + 4 * 0)] = 2;   // wall point: kept
  GridOptions o;
  o.iblank = true;
  o.big_endian = false;
  const std::string xyz = write("ib.xyz", gridFile(blocks, o));
  auto r = importFiles({xyz}, 6);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->report.dropped_cells, 9u);
  EXPECT_EQ(r->mesh.numTets(), (27u - 9u) * 6u);
  EXPECT_EQ(r->mesh.numPoints(), 64u);
  const Field* ib = r->mesh.findPointField("iblank");
  ASSERT_TRUE(ib);
  EXPECT_EQ(ib->type, ScalarType::kInt32);
  EXPECT_EQ(ib->components, 1u);
  ASSERT_EQ(ib->itemCount(), 64u);
  for (size_t p = 0; p < 64; ++p) EXPECT_EQ(ib->get(p, 0), blocks[0].iblank[p]) << p;
  EXPECT_TRUE(r->mesh.checkConsistency("iblank").isOk());
  // Independently: the points of the cells that have no hole vertex are the referenced ones.
  std::vector<int> used(64, 0);
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) {
        std::vector<int> corners;
        for (int c = 0; c < 8; ++c) corners.push_back((i + (c & 1)) + 4 * ((j + (c >> 1 & 1)) + 4 * (k + (c >> 2))));
        if (std::any_of(corners.begin(), corners.end(), [&](int v) { return blocks[0].iblank[v] == 0; })) continue;
        for (int v : corners) used[v] = 1;
      }
  EXPECT_EQ(used[2], 1);   // the fringe point
  EXPECT_EQ(used[12], 1);  // the wall point
  const MeshStats s = computeMeshStats(r->mesh);
  EXPECT_EQ(s.inverted, 0u);
  EXPECT_EQ(s.unreferenced_points, static_cast<uint64_t>(std::count(used.begin(), used.end(), 0)));
}

TEST_F(Plot3dSynthetic, LeftHandedBlockIsFlipped) {
  Block b = boxBlock(3, 3, 3);
  const std::string right = write("right.xyz", gridFile({b}, GridOptions()));
  for (double& x : b.x) x = -x;  // mirror: every cell left-handed
  const std::string left = write("left.xyz", gridFile({b}, GridOptions()));
  // Every tetrahedron of a left-handed grid is flipped, none of a right-handed one, with either split.
  for (int split : {5, 6}) {
    SCOPED_TRACE(split);
    auto r = importFiles({left}, split);
    ASSERT_TRUE(r.isOk()) << r.status().message();
    EXPECT_EQ(r->report.flipped, 8u * split);
    EXPECT_EQ(computeMeshStats(r->mesh).inverted, 0u);
    auto l = importFiles({right}, split);
    ASSERT_TRUE(l.isOk()) << l.status().message();
    EXPECT_EQ(l->report.flipped, 0u);
    // The same tetrahedra, corner for corner, apart from the exchanged pair that a flip makes.
    ASSERT_EQ(r->mesh.tets.size(), l->mesh.tets.size());
    for (size_t t = 0; t < r->mesh.tets.size(); ++t) {
      const Tet& a = r->mesh.tets[t];
      const Tet& c = l->mesh.tets[t];
      EXPECT_TRUE(a[0] == c[0] && a[1] == c[1] && a[2] == c[3] && a[3] == c[2]) << t;
    }
  }
}

TEST_F(Plot3dSynthetic, FunctionFileAsSecondAndThirdInput) {
  const std::vector<Block> blocks = {boxBlock(3, 4, 2)};
  GridOptions o;
  const std::string xyz = write("f.xyz", gridFile(blocks, o));
  const std::string q = write("f.q", qFile(blocks, o));
  const std::string fun = write("f.f", functionFile(blocks, o, 2));
  auto second = importFiles({xyz, fun});
  ASSERT_TRUE(second.isOk()) << second.status().message();
  EXPECT_FALSE(second->mesh.findPointField("density"));
  ASSERT_TRUE(second->mesh.findPointField("function_0") && second->mesh.findPointField("function_1"));
  EXPECT_EQ(second->mesh.findPointField("function_1")->get(5, 0), 105.0);
  auto third = importFiles({xyz, q, fun});
  ASSERT_TRUE(third.isOk()) << third.status().message();
  EXPECT_TRUE(third->mesh.findPointField("density"));
  ASSERT_TRUE(third->mesh.findPointField("function_1"));
  EXPECT_EQ(third->mesh.findPointField("function_0")->get(23, 0), 23.0);
}

// A second file that fits the grid neither as a Q file nor as a function file is refused, named,
// for both readings (each reads the file as it is on disk).
TEST_F(Plot3dSynthetic, SecondFileThatFitsNeitherReadingIsNamed) {
  const std::vector<Block> blocks = {boxBlock(3, 4, 2)};
  GridOptions o;
  const std::string xyz = write("n.xyz", gridFile(blocks, o));
  const std::string junk = write("n.q", std::string(1001, '\x01'));
  auto r = importFiles({xyz, junk});
  ASSERT_FALSE(r.isOk());
  const std::string& m = r.status().message();
  EXPECT_NE(m.find(junk + ": neither a PLOT3D Q file nor a function file for the grid"), std::string::npos) << m;
  EXPECT_NE(m.find("as a Q file: "), std::string::npos) << m;
  EXPECT_NE(m.find("as a function file: "), std::string::npos) << m;
  // The function file's reading still works after the Q file's failed.
  const std::string fun = write("n.f", functionFile(blocks, o, 2));
  auto ok = importFiles({xyz, fun});
  ASSERT_TRUE(ok.isOk()) << ok.status().message();
  EXPECT_EQ(ok->mesh.findPointField("function_1")->get(5, 0), 105.0);
}

TEST_F(Plot3dSynthetic, TwoDimensionalGridIsRejected) {
  Bytes b;
  b.i32(5);
  b.i32(4);
  for (int a = 0; a < 2; ++a)
    for (int p = 0; p < 20; ++p) b.real(a * 10.0 + p, 4);
  const std::string xyz = write("flat.xyz", b.s);
  auto r = importFiles({xyz});
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kUnsupported);
  EXPECT_NE(r.status().message().find("2D"), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find("5x4"), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find(xyz), std::string::npos);

  // A 3D file with a dimension of 1 is a 2D grid too.
  const std::string thin = write("thin.xyz", gridFile({boxBlock(4, 3, 1)}, GridOptions()));
  auto t = importFiles({thin});
  ASSERT_FALSE(t.isOk());
  EXPECT_NE(t.status().message().find("4x3x1"), std::string::npos) << t.status().message();
}

// Ints 1 1 1 2 then six float32: "single grid 1x1x1, float64 + IBLANK" and "multi-grid, 1 grid
// 1x1x2, float32" both fit its 40 bytes exactly.
std::string ambiguousGrid() {
  Bytes b;
  for (int v : {1, 1, 1, 2}) b.i32(v);
  for (int p = 0; p < 6; ++p) b.real(0.5 * p, 4);
  return b.s;
}

TEST_F(Plot3dSynthetic, AmbiguousFileIsRejectedWithTheCandidates) {
  const std::string xyz = write("amb.xyz", ambiguousGrid());
  auto r = importFiles({xyz});
  ASSERT_FALSE(r.isOk());
  const std::string& m = r.status().message();
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidData);
  EXPECT_NE(m.find("ambiguous"), std::string::npos) << m;
  EXPECT_NE(m.find("single grid, 3D, float64, IBLANK: grids 1x1x1"), std::string::npos) << m;
  EXPECT_NE(m.find("multi-grid, 3D, float32, no IBLANK: grids 1x1x2"), std::string::npos) << m;

  // A .p3d meta-file that names the layout settles it.
  write("amb.p3d", R"({"multi-grid": true, "precision": 32, "filenames": [{"xyz": "amb.xyz"}]})");
  auto settled = importFiles({dir_ + "/amb.p3d"});
  ASSERT_FALSE(settled.isOk());  // 1x1x2 is still a degenerate grid, but no longer ambiguous
  EXPECT_NE(settled.status().message().find("1x1x2"), std::string::npos) << settled.status().message();
  EXPECT_EQ(settled.status().message().find("ambiguous"), std::string::npos) << settled.status().message();
}

TEST_F(Plot3dSynthetic, TruncatedGridNamesFileOffsetAndReason) {
  const std::string full = test::readFile(dataPath("plot3d/bluntfinxyz.bin"));
  const std::string xyz = write("trunc.xyz", full.substr(0, 400000));
  auto r = importFiles({xyz});
  ASSERT_FALSE(r.isOk());
  const std::string& m = r.status().message();
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidData);
  EXPECT_NE(m.find(xyz), std::string::npos) << m;
  EXPECT_NE(m.find("big-endian, no record markers, single grid, 3D, float32, no IBLANK: grid 1 (40x32x32) data "
                   "needs 491520 bytes at byte 12, the file has 399988 left"),
            std::string::npos)
      << m;
  EXPECT_NE(m.find("text files are read as ASCII PLOT3D"), std::string::npos) << m;

  // Every shorter prefix fails cleanly too (a sample of them, to keep the test fast).
  for (size_t len : {1u, 4u, 11u, 12u, 13u, 491531u}) {
    const std::string p = write("prefix.xyz", full.substr(0, len));
    auto t = importFiles({p});
    EXPECT_FALSE(t.isOk()) << len;
  }
}

TEST_F(Plot3dSynthetic, BadInputsFailWithTheFileNamed) {
  const std::string empty = write("empty.xyz", "");
  auto e = importFiles({empty});
  ASSERT_FALSE(e.isOk());
  EXPECT_EQ(e.status().code(), StatusCode::kInvalidData);
  EXPECT_NE(e.status().message().find(empty), std::string::npos);
  EXPECT_NE(e.status().message().find("empty"), std::string::npos);

  const std::string sub = dir_ + "/adir.xyz";
  std::filesystem::create_directories(sub);
  auto d = importFiles({sub});
  ASSERT_FALSE(d.isOk());
  EXPECT_EQ(d.status().code(), StatusCode::kIo);
  EXPECT_NE(d.status().message().find(sub), std::string::npos);

  auto missing = importFiles({dir_ + "/missing.xyz"});
  ASSERT_FALSE(missing.isOk());
  EXPECT_EQ(missing.status().code(), StatusCode::kIo);

  // Non-zero bytes after the grid are an error, zero bytes a warning.
  const std::string grid = gridFile({boxBlock(3, 3, 3)}, GridOptions());
  auto junk = importFiles({write("junk.xyz", grid + std::string("\1\0\0\0", 4))});
  ASSERT_FALSE(junk.isOk());
  EXPECT_NE(junk.status().message().find("not all zero"), std::string::npos) << junk.status().message();
  auto padded = importFiles({write("pad.xyz", grid + std::string(8, '\0'))});
  ASSERT_TRUE(padded.isOk()) << padded.status().message();
  ASSERT_EQ(padded->report.warnings.size(), 1u);
  EXPECT_NE(padded->report.warnings[0].find("8 trailing zero bytes"), std::string::npos);

  // An impossible dimension in a record whose markers check out is named as such.
  Block flat = boxBlock(3, 3, 3);
  flat.n[1] = 0;
  GridOptions marked;
  marked.marker = 4;
  auto zero = importFiles({write("zero.xyz", gridFile({flat}, marked))});
  ASSERT_FALSE(zero.isOk());
  EXPECT_NE(zero.status().message().find("[1] big-endian, 4-byte record markers, single grid, 3D, float32, no IBLANK: "
                                         "dimension 2 of grid 1 is 0"),
            std::string::npos)
      << zero.status().message();

  // Text is not read, and the message says so.
  auto text = importFiles({write("ascii.xyz", "3 3 3\n0 1 2 0 1 2 0 1 2\n")});
  ASSERT_FALSE(text.isOk());
  EXPECT_NE(text.status().message().find("ASCII"), std::string::npos);

  // A record marker that disagrees with its closing marker.
  GridOptions o;
  o.marker = 4;
  std::string bad = gridFile({boxBlock(3, 3, 3)}, o);
  bad[bad.size() - 1] ^= 1;
  auto m = importFiles({write("badmarker.xyz", bad)});
  ASSERT_FALSE(m.isOk());
  EXPECT_NE(m.status().message().find("closing marker"), std::string::npos) << m.status().message();

  // An absurd dimension must not make the reader allocate: it is rejected by size.
  Bytes huge;
  for (int v : {1 << 30, 1 << 30, 1 << 30}) huge.i32(v);
  huge.s += std::string(64, '\0');
  EXPECT_FALSE(importFiles({write("huge.xyz", huge.s)}).isOk());
}

TEST_F(Plot3dSynthetic, QDimensionsMustMatchTheGrid) {
  const std::vector<Block> blocks = {boxBlock(3, 3, 3)};
  const std::string xyz = write("g.xyz", gridFile(blocks, GridOptions()));
  const std::string q = write("g.q", qFile({boxBlock(3, 3, 4)}, GridOptions()));
  auto r = importFiles({xyz, q});
  ASSERT_FALSE(r.isOk());
  const std::string& m = r.status().message();
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidData);
  EXPECT_NE(m.find(q), std::string::npos) << m;
  EXPECT_NE(m.find("3x3x4"), std::string::npos) << m;
  EXPECT_NE(m.find("disagree"), std::string::npos) << m;
  EXPECT_NE(m.find("3x3x3"), std::string::npos) << m;

  // A Q file truncated in its data says where.
  const std::string full_q = qFile(blocks, GridOptions());
  const std::string cut = write("t.q", full_q.substr(0, full_q.size() - 10));
  auto t = importFiles({xyz, cut});
  ASSERT_FALSE(t.isOk());
  EXPECT_NE(t.status().message().find(cut), std::string::npos) << t.status().message();
  EXPECT_NE(t.status().message().find("grid 1 (3x3x3) data needs 540 bytes at byte 28, the file has 530 left"),
            std::string::npos)
      << t.status().message();

  // Cut inside its dimensions record, next to a grid with record markers: the reading with the
  // grid's layout is named first, with the record that does not fit.
  GridOptions marked;
  marked.marker = 4;
  marked.multi = true;
  const std::string mxyz = write("m.xyz", gridFile(blocks, marked));
  const std::string mq = qFile(blocks, marked);
  const std::string mcut = write("m.q", mq.substr(0, 20));
  auto c = importFiles({mxyz, mcut});
  ASSERT_FALSE(c.isOk());
  EXPECT_NE(c.status().message().find("as a Q file read like its grid (big-endian, 4-byte record markers, multi-grid, "
                                      "float32): dimensions: the record marker at byte 12 says 12 bytes, past the end "
                                      "of the file"),
            std::string::npos)
      << c.status().message();
}

TEST_F(Plot3dSynthetic, MetaFileNamesTheFilesRelativeToItself) {
  const std::vector<Block> blocks = {boxBlock(3, 4, 3)};
  GridOptions o;
  o.big_endian = false;
  o.marker = 4;
  std::filesystem::create_directories(dir_ + "/sub");
  write("sub/m.xyz", gridFile(blocks, o));
  write("sub/m.q", qFile(blocks, o));
  write("sub/m.f", functionFile(blocks, o, 3));
  const std::string meta = write("sub/case.p3d", R"({
    "auto-detect-format": false, "format": "binary", "byte-order": "little", "precision": 32,
    "multi-grid": false, "blanking": false, "language": "Fortran",
    "filenames": [ {"time": 2.0, "xyz": "m.xyz"}, {"time": 1.0, "xyz": "m.xyz", "q": "m.q", "function": "m.f"} ]
  })");
  auto r = importFiles({meta});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  expectCoords(r->mesh, blocks, 4);
  EXPECT_TRUE(r->mesh.findPointField("density"));  // the entry with the smallest time
  EXPECT_TRUE(r->mesh.findPointField("function_2"));
  EXPECT_EQ(r->mesh.numTets(), 2u * 3u * 2u * 6u);

  // Its layout keys are constraints: a wrong byte order finds nothing.
  write("sub/wrong.p3d", R"({"byte-order": "big", "filenames": [{"xyz": "m.xyz"}]})");
  auto wrong = importFiles({dir_ + "/sub/wrong.p3d"});
  ASSERT_FALSE(wrong.isOk());
  EXPECT_NE(wrong.status().message().find("m.xyz"), std::string::npos);

  write("sub/bad.p3d", R"({"filenames": [ {"q": "m.q"} ]})");
  auto bad = importFiles({dir_ + "/sub/bad.p3d"});
  ASSERT_FALSE(bad.isOk());
  EXPECT_NE(bad.status().message().find("xyz"), std::string::npos);

  write("sub/broken.p3d", "{ \"filenames\": [ ");
  EXPECT_FALSE(importFiles({dir_ + "/sub/broken.p3d"}).isOk());
}

TEST_F(Plot3dSynthetic, MetaFileTakesParaViewsSpellingOfLanguage) {
  // ParaView's vtkPlot3DMetaReader knows "C" and "fortran" (lower case) only: its meta-files say so.
  const std::vector<Block> blocks = {boxBlock(3, 4, 3)};
  GridOptions o;
  o.big_endian = false;
  o.marker = 4;
  write("lang.xyz", gridFile(blocks, o));
  const std::string meta = write("lang.p3d", R"({
    "auto-detect-format": false, "byte-order": "little", "precision": 32, "multi-grid": false,
    "language": "fortran", "filenames": [ {"time": 0, "xyz": "lang.xyz"} ]
  })");
  auto r = importFiles({meta});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  expectCoords(r->mesh, blocks, 4);

  // "C" means no record markers: this file has them, so nothing fits.
  write("lang_c.p3d", R"({"auto-detect-format": false, "language": "C", "filenames": [{"xyz": "lang.xyz"}]})");
  EXPECT_FALSE(importFiles({dir_ + "/lang_c.p3d"}).isOk());

  write("lang_bad.p3d", R"({"language": "cobol", "filenames": [{"xyz": "lang.xyz"}]})");
  auto bad = importFiles({dir_ + "/lang_bad.p3d"});
  ASSERT_FALSE(bad.isOk());
  EXPECT_NE(bad.status().message().find("\"fortran\""), std::string::npos) << bad.status().message();
}

// ParaView's "function-names" name the function file's variables in order; variables beyond the list
// keep function_k.
TEST_F(Plot3dSynthetic, MetaFileNamesTheFunctionVariables) {
  const std::vector<Block> blocks = {boxBlock(3, 4, 3)};
  GridOptions o;
  write("fn.xyz", gridFile(blocks, o));
  write("fn.q", qFile(blocks, o));
  write("fn.f", functionFile(blocks, o, 3));
  const std::string plain =
      write("plain.p3d", R"({"filenames": [{"xyz": "fn.xyz", "q": "fn.q", "function": "fn.f"}]})");
  auto unnamed = importFiles({plain});
  ASSERT_TRUE(unnamed.isOk()) << unnamed.status().message();
  const std::string named = write("named.p3d", R"({"function-names": ["pressure", "temperature"],
    "filenames": [{"xyz": "fn.xyz", "q": "fn.q", "function": "fn.f"}]})");
  auto r = importFiles({named});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  const std::pair<const char*, const char*> renamed[] = {
      {"pressure", "function_0"}, {"temperature", "function_1"}, {"function_2", "function_2"}};
  for (const auto& [name, was] : renamed) {
    const Field* f = r->mesh.findPointField(name);
    const Field* g = unnamed->mesh.findPointField(was);
    ASSERT_TRUE(f && g) << name;
    EXPECT_EQ(f->bytes, g->bytes) << name;
  }
  EXPECT_FALSE(r->mesh.findPointField("function_0"));
  for (const std::string& w : r->report.warnings) EXPECT_EQ(w.find("function-names"), std::string::npos) << w;

  // More names than variables: a warning; a name twice, a name of a Q field, or not a list: errors.
  write("more.p3d",
        R"({"function-names": ["a", "b", "c", "d"], "filenames": [{"xyz": "fn.xyz", "function": "fn.f"}]})");
  auto more = importFiles({dir_ + "/more.p3d"});
  ASSERT_TRUE(more.isOk()) << more.status().message();
  EXPECT_TRUE(more->mesh.findPointField("c"));
  bool warned = false;
  for (const std::string& w : more->report.warnings)
    warned |= w.find("lists 4 names for the 3 variables") != std::string::npos;
  EXPECT_TRUE(warned);
  write("twice.p3d", R"({"function-names": ["a", "a"], "filenames": [{"xyz": "fn.xyz", "function": "fn.f"}]})");
  auto twice = importFiles({dir_ + "/twice.p3d"});
  ASSERT_FALSE(twice.isOk());
  EXPECT_NE(twice.status().message().find("lists \"a\" twice"), std::string::npos) << twice.status().message();
  write("clash.p3d",
        R"({"function-names": ["density"], "filenames": [{"xyz": "fn.xyz", "q": "fn.q", "function": "fn.f"}]})");
  auto clash = importFiles({dir_ + "/clash.p3d"});
  ASSERT_FALSE(clash.isOk());
  EXPECT_NE(clash.status().message().find("clash.p3d: key \"function-names\": \"density\""), std::string::npos)
      << clash.status().message();
  write("notlist.p3d", R"({"function-names": "p", "filenames": [{"xyz": "fn.xyz", "function": "fn.f"}]})");
  EXPECT_FALSE(importFiles({dir_ + "/notlist.p3d"}).isOk());
}

TEST_F(Plot3dSynthetic, WeldMergesBitIdenticalPointsAndDropsCollapsedTets) {
  // One cell whose top face collapses to a point: a pyramid.
  Block b = boxBlock(2, 2, 2);
  for (size_t p = 4; p < 8; ++p) {
    b.x[p] = 0.5;
    b.y[p] = 0.5;
    b.z[p] = 1.0;
  }
  const std::string xyz = write("apex.xyz", gridFile({b}, GridOptions()));
  auto plain = importFiles({xyz}, 6);
  ASSERT_TRUE(plain.isOk()) << plain.status().message();
  EXPECT_EQ(plain->mesh.numPoints(), 8u);
  EXPECT_EQ(plain->mesh.numTets(), 6u);
  EXPECT_EQ(plain->report.zero_volume, 4u);

  auto six = importFiles({xyz}, 6, true);
  ASSERT_TRUE(six.isOk()) << six.status().message();
  EXPECT_EQ(six->report.welded_points, 3u);
  EXPECT_EQ(six->report.collapsed_tets, 4u);
  EXPECT_EQ(six->mesh.numPoints(), 5u);
  EXPECT_EQ(six->mesh.numTets(), 2u);
  EXPECT_EQ(six->report.zero_volume, 0u);
  const MeshStats s = computeMeshStats(six->mesh);
  EXPECT_EQ(s.coincident_points, 0u);
  EXPECT_EQ(s.unreferenced_points, 0u);
  EXPECT_EQ(s.inverted, 0u);

  auto five = importFiles({xyz}, 5, true);
  ASSERT_TRUE(five.isOk()) << five.status().message();
  EXPECT_EQ(five->report.welded_points, 3u);
  EXPECT_EQ(five->report.collapsed_tets, 3u);
  EXPECT_EQ(five->mesh.numTets(), 2u);

  // Real data: welding the blunt fin merges its singular lines.
  auto fin = importFiles({dataPath("plot3d/bluntfinxyz.bin"), dataPath("plot3d/bluntfinq.bin")}, 6, true);
  ASSERT_TRUE(fin.isOk()) << fin.status().message();
  const MeshStats fs = computeMeshStats(fin->mesh);
  EXPECT_GT(fin->report.welded_points, 0u);
  EXPECT_EQ(fs.points, 40960u - fin->report.welded_points);
  EXPECT_EQ(fs.tets, 39u * 31u * 31u * 6u - fin->report.collapsed_tets);
  EXPECT_EQ(fs.coincident_points, 0u);
  EXPECT_EQ(fs.inverted, 0u);
  EXPECT_EQ(fin->mesh.findPointField("density")->itemCount(), fs.points);
}

// ---- Welded seams between blocks -----------------------------------------------------------------

// A block whose point (i, j, k) is at p(i, j, k).
Block mappedBlock(int ni, int nj, int nk, const std::function<std::array<double, 3>(int, int, int)>& p) {
  Block b{{ni, nj, nk}, {}, {}, {}, {}};
  for (int k = 0; k < nk; ++k)
    for (int j = 0; j < nj; ++j)
      for (int i = 0; i < ni; ++i) {
        const std::array<double, 3> q = p(i, j, k);
        b.x.push_back(q[0]);
        b.y.push_back(q[1]);
        b.z.push_back(q[2]);
      }
  return b;
}

// boxBlock's point (i, j, k) of the box starting at x = origin.
std::array<double, 3> boxPoint(int i, int j, int k, double origin) {
  return {origin + i + 0.125 * j, j + 0.25 * k, k + 0.0625 * (origin + i)};
}

// A ring of `blocks` annular sectors around the z axis (i radial, r from 1 to 2; j around, each block
// `cells` cells of it; k along z), every seam a plane through the axis; the last block ends where the
// first begins, bit for bit.
std::vector<Block> ringBlocks(int blocks, int cells) {
  std::vector<Block> out;
  const int around = blocks * cells;
  for (int b = 0; b < blocks; ++b)
    out.push_back(mappedBlock(3, cells + 1, 3, [&](int i, int j, int k) {
      const double t = 2 * M_PI * ((b * cells + j) % around) / around, r = 1 + 0.5 * i;
      return std::array<double, 3>{r * std::cos(t), r * std::sin(t), 0.5 * k};
    }));
  return out;
}

// What the validator says about a mesh's non-conforming interfaces (boundary triangles), and that it
// finds no error.
uint64_t nonconforming(const TetMesh& mesh) {
  ValidationReport report;
  checkMesh(mesh, "/mesh", report);
  EXPECT_FALSE(report.hasErrors()) << report.toText("mesh");
  return report.count(IssueCode::kNonconformingInterface);
}

std::vector<std::string> seamWarnings(const ImportReport& r) {
  std::vector<std::string> out;
  for (const std::string& w : r.warnings)
    if (w.rfind("--weld:", 0) == 0) out.push_back(w);
  return out;
}

TEST_F(Plot3dSynthetic, WeldedBlocksOfOppositeParityConformWithSplitFive) {
  // The second block starts where the first (3 cells along i) ends: at their seam the first has odd
  // i + j + k where the second has even, so cutting both with parity i + j + k leaves the seam's 4
  // quadrilaterals as 16 boundary triangles inside the volume. In the second, the same box is indexed
  // with its axes permuted and one of them reversed.
  const Block whole = boxBlock(6, 3, 3);
  const Block first = boxBlock(4, 3, 3), second = boxBlock(3, 3, 3, 3.0);
  const Block turned = mappedBlock(3, 3, 3, [](int i, int j, int k) { return boxPoint(k, 2 - j, i, 3.0); });
  GridOptions o;
  o.multi = true;
  o.precision = 8;
  const std::string one = write("whole.xyz", gridFile({whole}, o));
  auto single = importFiles({one}, 5);
  ASSERT_TRUE(single.isOk()) << single.status().message();
  const MeshStats ss = computeMeshStats(single->mesh);
  for (const Block& b : {second, turned}) {
    const std::string xyz = write("two.xyz", gridFile({first, b}, o));
    auto r = importFiles({xyz}, 5, true);
    ASSERT_TRUE(r.isOk()) << r.status().message();
    const MeshStats s = computeMeshStats(r->mesh);
    EXPECT_EQ(r->report.welded_points, 9u);
    EXPECT_EQ(s.points, ss.points);
    EXPECT_EQ(s.tets, ss.tets);
    EXPECT_EQ(s.boundary_faces, ss.boundary_faces);
    EXPECT_EQ(s.faces, ss.faces);
    EXPECT_EQ(s.non_manifold_faces, 0u);
    EXPECT_NEAR(s.total_volume, ss.total_volume, 1e-12);
    EXPECT_EQ(nonconforming(r->mesh), 0u);
    EXPECT_EQ(seamWarnings(r->report), std::vector<std::string>{});
  }
  // The 6-split cuts every face along its diagonal of increasing indices: in the turned block that is
  // the seam's other diagonal, which no choice can change. The convert warns, naming the grids, and
  // the validator finds the 16 triangles.
  const std::string xyz = write("turned.xyz", gridFile({first, turned}, o));
  auto six = importFiles({xyz}, 6, true);
  ASSERT_TRUE(six.isOk()) << six.status().message();
  EXPECT_EQ(computeMeshStats(six->mesh).boundary_faces,
            computeMeshStats(importFiles({one}, 6)->mesh).boundary_faces + 16);
  EXPECT_EQ(nonconforming(six->mesh), 16u);
  const std::vector<std::string> w = seamWarnings(six->report);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("grids 1 and 2 meet at 4 cell faces, 4 of which --split 6 cuts along different diagonals"),
            std::string::npos)
      << w[0];
  EXPECT_NE(w[0].find("NONCONFORMING_INTERFACE"), std::string::npos) << w[0];
  // Unwelded, the blocks stay apart: nothing to conform.
  auto apart = importFiles({xyz}, 6);
  ASSERT_TRUE(apart.isOk());
  EXPECT_EQ(nonconforming(apart->mesh), 0u);
  EXPECT_EQ(seamWarnings(apart->report), std::vector<std::string>{});
}

TEST_F(Plot3dSynthetic, WeldedRingsConformWhereTheirParitiesAllowIt) {
  GridOptions o;
  o.multi = true;
  o.precision = 8;
  // Rings of blocks, each seam asking for the two blocks' parities to differ (3 cells per block) or
  // agree (2): an even ring, or agreeing seams, conform all around; the parities propagate block to
  // block.
  for (const auto& [blocks, cells] : std::vector<std::pair<int, int>>{{4, 3}, {3, 2}, {2, 3}, {1, 4}}) {
    SCOPED_TRACE(std::to_string(blocks) + " blocks of " + std::to_string(cells) + " cells");
    const std::string xyz = write("ring.xyz", gridFile(ringBlocks(blocks, cells), o));
    auto r = importFiles({xyz}, 5, true);
    ASSERT_TRUE(r.isOk()) << r.status().message();
    const MeshStats s = computeMeshStats(r->mesh);
    // The inner and outer walls and the two ends: 2 x 2 quadrilaterals per cell around each, 2
    // triangles per quadrilateral.
    EXPECT_EQ(s.boundary_faces, static_cast<uint64_t>(blocks * cells) * 4 * 2 * 2);
    EXPECT_EQ(s.non_manifold_faces, 0u);
    EXPECT_EQ(s.inverted, 0u);
    EXPECT_EQ(nonconforming(r->mesh), 0u);
    EXPECT_EQ(seamWarnings(r->report), std::vector<std::string>{});
  }
  // An odd ring of seams that each ask for different parities, and one block around with an odd number
  // of cells (meeting itself): one seam cannot conform. The convert warns naming its grids, and the
  // validator finds its 4 quadrilaterals covered from both sides (16 triangles).
  for (const auto& [blocks, cells, who] :
       std::vector<std::tuple<int, int, std::string>>{{3, 3, "grids 2 and 3 meet"}, {1, 9, "grid 1 meets itself"}}) {
    SCOPED_TRACE(who);
    const std::string xyz = write("odd.xyz", gridFile(ringBlocks(blocks, cells), o));
    auto r = importFiles({xyz}, 5, true);
    ASSERT_TRUE(r.isOk()) << r.status().message();
    EXPECT_EQ(computeMeshStats(r->mesh).boundary_faces, static_cast<uint64_t>(blocks * cells) * 4 * 2 * 2 + 16);
    EXPECT_EQ(nonconforming(r->mesh), 16u);
    const std::vector<std::string> w = seamWarnings(r->report);
    ASSERT_EQ(w.size(), 1u);
    EXPECT_NE(w[0].find(who + " at 4 cell faces, 4 of which --split 5 cuts along different diagonals"),
              std::string::npos)
        << w[0];
  }
}

TEST_F(Plot3dSynthetic, ConvertWarnsOfASeamThatCannotConformAndValidateReportsIt) {
  GridOptions o;
  o.multi = true;
  o.precision = 8;
  const std::string xyz = write("odd.xyz", gridFile(ringBlocks(3, 3), o));
  const std::string out = dir_ + "/odd.gtn";
  const test::RunResult c = test::runGtn("convert " + xyz + " --split 5 --weld --levels 1 -o " + out);
  ASSERT_EQ(c.exit_code, 0) << c.err;
  EXPECT_NE(c.err.find("grids 2 and 3 meet at 4 cell faces"), std::string::npos) << c.err;
  const test::RunResult v = test::runGtn("validate " + out + " --json");
  EXPECT_EQ(v.exit_code, 0) << v.out << v.err;
  EXPECT_NE(v.out.find("NONCONFORMING_INTERFACE"), std::string::npos) << v.out;
  const test::RunResult src = test::runGtn("validate " + xyz + " --split 5 --weld");
  EXPECT_NE(src.out.find("NONCONFORMING_INTERFACE"), std::string::npos) << src.out;
  // An even ring conforms: nothing to say.
  const std::string even = write("even.xyz", gridFile(ringBlocks(4, 3), o));
  const test::RunResult e = test::runGtn("convert " + even + " --split 5 --weld --levels 1 -o " + dir_ + "/even.gtn");
  ASSERT_EQ(e.exit_code, 0) << e.err;
  EXPECT_EQ(e.err.find("--weld:"), std::string::npos) << e.err;
  const test::RunResult ev = test::runGtn("validate " + dir_ + "/even.gtn");
  EXPECT_EQ(ev.exit_code, 0) << ev.out;
  EXPECT_EQ(ev.out.find("NONCONFORMING_INTERFACE"), std::string::npos) << ev.out;
}

// ---- Sample generator and CLI --------------------------------------------------------------------

std::string makeSampleBinary() {
  return (std::filesystem::path(GTN_BINARY).parent_path() / "gtn-make-sample").string();
}

TEST(Plot3dSample, GeneratorWritesAValidDeterministicSample) {
  const std::string a = test::tempDir("plot3d-sample-a"), b = test::tempDir("plot3d-sample-b");
  ASSERT_EQ(test::runShell(makeSampleBinary() + " " + a).exit_code, 0);
  ASSERT_EQ(test::runShell(makeSampleBinary() + " " + b).exit_code, 0);
  const std::string xyz = test::readFile(a + "/sample.xyz");
  EXPECT_EQ(xyz.size(), 12u + 24u * 16u * 12u * 12u);
  EXPECT_EQ(xyz, test::readFile(b + "/sample.xyz"));
  EXPECT_EQ(test::readFile(a + "/sample.q"), test::readFile(b + "/sample.q"));
  for (int split : {5, 6}) {
    auto r = importFiles({a + "/sample.xyz", a + "/sample.q"}, split);
    ASSERT_TRUE(r.isOk()) << r.status().message();
    EXPECT_TRUE(r->report.warnings.empty());
    // Right-handed cells: both splits' tables are positively oriented, so nothing is flipped.
    EXPECT_EQ(r->report.flipped, 0u);
    EXPECT_EQ(r->report.zero_volume, 0u);
    const MeshStats s = computeMeshStats(r->mesh);
    EXPECT_EQ(s.points, 24u * 16u * 12u);
    EXPECT_EQ(s.tets, 23u * 15u * 11u * static_cast<unsigned>(split));
    EXPECT_EQ(s.inverted, 0u);
    EXPECT_EQ(s.non_manifold_faces, 0u);
    EXPECT_EQ(s.coincident_points, 0u);
    ASSERT_EQ(s.fields.size(), 3u);
    EXPECT_GT(s.fields[0].min, 0.0);  // density
    EXPECT_GT(s.fields[2].min, 0.0);  // stagnation energy
    EXPECT_EQ(s.fields[0].non_finite + s.fields[1].non_finite + s.fields[2].non_finite, 0u);
  }
  EXPECT_EQ(test::runShell(makeSampleBinary()).exit_code, 2);
  // Options are not taken for a directory to create.
  const test::RunResult help = test::runShell("cd " + a + " && " + makeSampleBinary() + " --help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("usage: gtn-make-sample OUTDIR"), std::string::npos) << help.out;
  EXPECT_FALSE(test::fileExists(a + "/--help"));
}

// The benchmarks' large grid: the same shape at other dimensions; bad dimensions are refused.
TEST(Plot3dSample, GeneratorTakesDimensions) {
  const std::string dir = test::tempDir("plot3d-sample-dims");
  const test::RunResult made = test::runShell(makeSampleBinary() + " " + dir + " 31 9 5");
  ASSERT_EQ(made.exit_code, 0) << made.err;
  EXPECT_EQ(test::readFile(dir + "/sample.xyz").size(), 12u + 31u * 9u * 5u * 12u);
  auto r = importFiles({dir + "/sample.xyz", dir + "/sample.q"}, 6);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  const MeshStats s = computeMeshStats(r->mesh);
  EXPECT_EQ(s.tets, 30u * 8u * 4u * 6u);
  EXPECT_EQ(s.inverted + s.zero_volume, 0u);
  for (const char* bad : {" 31 9", " 31 9 1", " 31 x 5", " 2000 2 2", " 1000 1000 100"}) {
    const test::RunResult r2 = test::runShell(makeSampleBinary() + " " + dir + bad);
    EXPECT_EQ(r2.exit_code, 2) << bad;
  }
}

TEST(Plot3dCli, InfoJsonOnBluntFin) {
  const test::RunResult info = test::runGtn("info " + dataPath("plot3d/bluntfinxyz.bin") + " " +
                                            dataPath("plot3d/bluntfinq.bin") + " --split 5 --json");
  ASSERT_EQ(info.exit_code, 0) << info.err;
  const nlohmann::json j = nlohmann::json::parse(info.out);
  EXPECT_EQ(j["points"], 40960);
  EXPECT_EQ(j["tets"], 187395);
  EXPECT_EQ(j["faces"], 381548);
  EXPECT_EQ(j["boundary_faces"], 13516);
  EXPECT_EQ(j["inverted"], 0);
  EXPECT_GT(j["zero_volume"].get<int>(), 0);
  ASSERT_TRUE(j["bbox"].contains("min") && j["bbox"].contains("max"));
  EXPECT_LT(j["bbox"]["min"][0].get<double>(), j["bbox"]["max"][0].get<double>());
  ASSERT_EQ(j["fields"].size(), 3u);
  EXPECT_EQ(j["fields"][0]["name"], "density");
  EXPECT_EQ(j["fields"][0]["components"], 1);
  EXPECT_EQ(j["fields"][0]["type"], "float32");
  EXPECT_NEAR(j["fields"][0]["min"].get<double>(), 0.1926, 5e-5);
  EXPECT_NEAR(j["fields"][0]["max"].get<double>(), 4.9775, 5e-5);
  EXPECT_EQ(j["fields"][1]["name"], "momentum");
  EXPECT_EQ(j["fields"][1]["components"], 3);
  EXPECT_EQ(j["fields"][1]["type"], "float32");
  EXPECT_LT(j["fields"][1]["min"].get<double>(), j["fields"][1]["max"].get<double>());
  EXPECT_EQ(j["fields"][2]["name"], "stagnation_energy");
  EXPECT_EQ(j["fields"][2]["components"], 1);
  EXPECT_EQ(j["metadata"]["source.format"], "plot3d");
  EXPECT_NE(info.err.find("484 trailing zero bytes"), std::string::npos) << info.err;
}

TEST(Plot3dCli, TruncatedInputFailsWithoutOutput) {
  const std::string dir = test::tempDir("plot3d-cli-trunc");
  const std::string xyz = dir + "/cut.xyz";
  test::writeFile(xyz, test::readFile(dataPath("plot3d/bluntfinxyz.bin")).substr(0, 300001));
  const std::string out = dir + "/x.vtu";
  const test::RunResult r = test::runGtn("convert " + xyz + " " + dataPath("plot3d/bluntfinq.bin") + " -o " + out);
  EXPECT_TRUE(r.exit_code == 1 || r.exit_code == 3) << r.exit_code << r.err;
  EXPECT_EQ(r.out, "");
  EXPECT_NE(r.err.find(xyz), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(test::fileExists(out));
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    EXPECT_EQ(entry.path().filename(), "cut.xyz") << "left behind: " << entry.path();
}

// ASCII PLOT3D as Fortran list-directed output and C printf write it: a multi-grid grid with IBLANK
// (values spread over lines, some comma-separated, D exponents) and its Q file.
std::string asciiGrid(const std::vector<Block>& blocks, bool multi, bool iblank) {
  std::string s;
  char buf[64];
  if (multi) s += std::to_string(blocks.size()) + "\n";
  for (const Block& b : blocks)
    s += std::to_string(b.n[0]) + " " + std::to_string(b.n[1]) + " " + std::to_string(b.n[2]) + "\n";
  for (const Block& b : blocks) {
    size_t col = 0;
    for (const std::vector<double>* axis : {&b.x, &b.y, &b.z})
      for (double v : *axis) {
        std::snprintf(buf, sizeof buf, "%.17E", v);
        std::string t = buf;
        if (col % 3 == 1) t[t.find('E')] = 'D';
        s += t + (++col % 4 == 0 ? "\n" : (col % 2 ? ", " : "  "));
      }
    s += "\n";
    if (iblank)
      for (size_t i = 0; i < b.points(); ++i)
        s += std::to_string(b.iblank.empty() ? 1 : b.iblank[i]) + (i % 10 == 9 ? "\n" : " ");
    s += "\n";
  }
  return s;
}

TEST_F(Plot3dSynthetic, AsciiMultiGridWithIblankAndQ) {
  Block a = boxBlock(3, 2, 2), b = boxBlock(2, 2, 3, 10.0);
  a.iblank.assign(a.points(), 1);
  a.iblank[0] = 0;  // one hole: the cell that has point 0 is dropped
  b.iblank.assign(b.points(), -1);
  const std::string xyz = write("grid.x", asciiGrid({a, b}, true, true));
  std::string q = "2\n3 2 2\n2 2 3\n";
  for (const Block* blk : {&a, &b}) {
    q += "0.5 2.0 1.0D+06 3.25\n";
    for (int var = 0; var < 5; ++var)
      for (size_t i = 0; i < blk->points(); ++i) q += std::to_string(var * 100 + static_cast<int>(i)) + " ";
    q += "\n";
  }
  const std::string qpath = write("grid.q", q);
  auto r = importFiles({xyz, qpath});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  const TetMesh& m = r->mesh;
  ASSERT_EQ(m.numPoints(), 24u);
  EXPECT_EQ(m.coords[3 * 1 + 0], a.x[1]);  // bit-exact from 17 significant digits
  EXPECT_EQ(m.coords[3 * 13 + 1], b.y[1]);
  EXPECT_EQ(m.coords[3 * 23 + 2], b.z[11]);
  EXPECT_EQ(r->report.dropped_cells, 1u);
  EXPECT_EQ(m.numTets(), 6u * (2 - 1) + 6u * 2);
  EXPECT_EQ(*m.findMetadata("plot3d.layout"), "ASCII, multi-grid, 3D, IBLANK");
  EXPECT_EQ(*m.findMetadata("plot3d.re"), "1000000");
  const Field* density = nullptr;
  const Field* blank = nullptr;
  for (const Field& f : m.point_fields) {
    if (f.name == "density") density = &f;
    if (f.name == "iblank") blank = &f;
  }
  ASSERT_NE(density, nullptr);
  ASSERT_NE(blank, nullptr);
  EXPECT_EQ(density->get(13, 0), 1.0);  // grid 2, point 1
  EXPECT_EQ(blank->get(0, 0), 0.0);
  EXPECT_EQ(blank->get(12, 0), -1.0);

  // A grid with a value too few, or a word among the numbers, fails naming the file and the reason.
  std::string cut = asciiGrid({a}, false, false);
  cut.erase(cut.find_last_of(" ,\n", cut.find_last_of("0123456789")));  // the last value
  cut += "\n";
  auto c = importFiles({write("cut.x", cut)});
  ASSERT_FALSE(c.isOk());
  EXPECT_NE(c.status().message().find("cut.x: not a PLOT3D grid file this reader understands: it is text (38 values) "
                                      "and no ASCII PLOT3D layout fits its value count"),
            std::string::npos)
      << c.status().message();
  auto w = importFiles({write("word.x", "2 2 2\n0 1 0 1 0 1 0 1\n0 0 1 1 0 0 1 1\n0 0 0 0 1 1 one 1\n")});
  ASSERT_FALSE(w.isOk());
  EXPECT_NE(w.status().message().find("word.x:4: ASCII PLOT3D: 'one' is not a number"), std::string::npos)
      << w.status().message();
}

}  // namespace
// A .p3d file is a meta-file when it is JSON text; otherwise it is a grid file itself, as gmsh's
// -format p3d (ASCII) and many CFD grids (binary) are named.
TEST_F(Plot3dSynthetic, P3dFileThatIsAGrid) {
  const std::vector<Block> blocks = {boxBlock(3, 4, 3)};
  GridOptions o;
  o.big_endian = true;
  o.marker = 0;
  for (const auto& [name, bytes, precision] :
       {std::tuple<std::string, std::string, int>{"binary.p3d", gridFile(blocks, o), 4},
        {"ascii.p3d", asciiGrid(blocks, true, false), 8}}) {
    SCOPED_TRACE(name);
    const std::string path = write(name, bytes);
    EXPECT_EQ(detectInputFormat(path), InputFormat::kPlot3d);
    auto r = importFiles({path});
    ASSERT_TRUE(r.isOk()) << r.status().message();
    expectCoords(r->mesh, blocks, precision);
    EXPECT_EQ(r->mesh.numTets(), 2u * 3u * 2u * 6u);
  }
  // JSON text after blanks is still a meta-file, and a damaged one says so.
  write("m.xyz", gridFile(blocks, o));
  auto meta = importFiles({write("meta.p3d", "\n  {\"filenames\": [{\"xyz\": \"m.xyz\"}]}")});
  ASSERT_TRUE(meta.isOk()) << meta.status().message();
  EXPECT_EQ(meta->mesh.numTets(), 2u * 3u * 2u * 6u);
  auto broken = importFiles({write("broken.p3d", "{ \"filenames\": [ ")});
  ASSERT_FALSE(broken.isOk());
  EXPECT_NE(broken.status().message().find("not a valid .p3d JSON meta-file"), std::string::npos)
      << broken.status().message();
}

}  // namespace gtn
