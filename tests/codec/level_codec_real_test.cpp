// Lossless round trips of the level codec on the real datasets, through the importers, with the
// compression and working-set targets the codec must meet.
#include <gtest/gtest.h>

#include <set>

#include "codec/level_codec.h"
#include "codec_test_util.h"
#include "convert/import.h"
#include "test_util.h"

namespace gtn {
namespace {

struct RealCase {
  std::vector<std::string> files;
  int split;
  // Boundary + peeling, per tetrahedron: below the cut-border machine's 2.04 (the goal; the
  // paper's 2.5 is its requirement), or less where a dataset does much better.
  double max_connectivity_bits;
};

// xz -9 size of the raw coordinate and field arrays as the source stores them.
size_t xzOfRawArrays(const TetMesh& m, const std::string& name) {
  std::string raw;
  for (double c : m.coords) {
    if (m.coord_type == ScalarType::kFloat32) {
      const float f = static_cast<float>(c);
      raw.append(reinterpret_cast<const char*>(&f), 4);
    } else {
      raw.append(reinterpret_cast<const char*>(&c), 8);
    }
  }
  for (const auto* list : {&m.point_fields, &m.cell_fields})
    for (const Field& f : *list) raw.append(reinterpret_cast<const char*>(f.bytes.data()), f.bytes.size());
  const std::string path = test::tempDir("codec_xz_" + name) + "/raw.bin";
  test::writeFile(path, raw);
  const test::RunResult r = test::runShell("xz -9 -c '" + path + "' | wc -c");
  EXPECT_EQ(r.exit_code, 0);
  return std::stoull(r.out);
}

TetMesh importOrDie(const RealCase& c) {
  std::vector<std::string> paths;
  for (const std::string& f : c.files) paths.push_back(test::dataPath(f));
  ImportOptions o;
  o.split = c.split;
  auto r = importMesh(paths, o);
  EXPECT_TRUE(r.isOk()) << r.status().message();
  return r.isOk() ? std::move(r->mesh) : TetMesh();
}

void checkCase(const RealCase& c, uint64_t* peak = nullptr) {
  const TetMesh m = importOrDie(c);
  ASSERT_GT(m.numTets(), 0u);
  const EncodedLevel e = test::roundTrip(m, peak);
  const double conn = 8.0 * (e.boundary.size() + e.connectivity.size()) / m.numTets();
  EXPECT_LT(conn, c.max_connectivity_bits) << c.files[0];
  // Coordinates + fields smaller than xz -9 of the raw arrays.
  size_t ours = e.geometry.size();
  for (const auto& s : e.point_fields) ours += s.size();
  for (const auto& s : e.cell_fields) ours += s.size();
  std::string name = c.files[0];
  for (char& ch : name)
    if (ch == '/' || ch == '.') ch = '_';
  EXPECT_LT(ours, xzOfRawArrays(m, name)) << c.files[0];
}

TEST(LevelCodecReal, SpxVtk) { checkCase({{"vtk/spx.vtk"}, 6, 2.04}); }

TEST(LevelCodecReal, BluntFinFiveSplitKeepsTheFrontSmall) {
  uint64_t peak = 0;
  checkCase({{"plot3d/bluntfinxyz.bin", "plot3d/bluntfinq.bin"}, 5, 1.0}, &peak);
  EXPECT_LE(peak, 40960u / 2) << "peak live vertices must stay at most half of the points";
}

// The renderer decodes the one field it shows. Blunt fin's three fields share no component, so each
// decoded alone leaves the other two as zeros; lv_guccione has ten point fields (float64, up to nine
// components each) and two cell fields.
TEST(LevelCodecReal, EachFieldDecodesAlone) {
  const RealCase fin{{"plot3d/bluntfinxyz.bin", "plot3d/bluntfinq.bin"}, 5, 1.0};
  auto e = encodeLevel(importOrDie(fin), EncodeOptions());
  ASSERT_TRUE(e.isOk()) << e.status().message();
  EXPECT_EQ(test::expectFieldsDecodeAlone(*e, /*unselected_zero=*/true), 3);
  const TetMesh lv = importOrDie({{"vtu/lv_guccione.vtu"}, 6, 2.04});
  ASSERT_EQ(lv.point_fields.size() + lv.cell_fields.size(), 12u);
  e = encodeLevel(lv, EncodeOptions());
  ASSERT_TRUE(e.isOk()) << e.status().message();
  EXPECT_EQ(test::expectFieldsDecodeAlone(*e, /*unselected_zero=*/false), 12);
}

TEST(LevelCodecReal, TetgenCornellSpheres) { checkCase({{"tetgen/cornell_spheres.1.ele"}, 6, 2.04}); }

// 331 points printed with 8 decimals, whose repeated decimal patterns xz -9 finds in the raw float64
// values: the closest of the shared datasets to xz.
TEST(LevelCodecReal, TetgenCornellBoxWithRegionAttribute) { checkCase({{"tetgen/cornellbox_orig.1.ele"}, 6, 2.04}); }

TEST(LevelCodecReal, VtuWithManyFieldsAndUnusedPoints) {
  checkCase({{"vtu/lv_guccione.vtu"}, 6, 2.04});
  checkCase({{"vtu/raptorTetra_19409.vtu"}, 6, 2.04});
  checkCase({{"vtu/fire_ug.vtu"}, 6, 2.04});
}

// A quadratic mesh as importers keep it (spec 10.5, edge points): spx's tetrahedra, with a node that no
// tetrahedron uses on each of their edges, as VTK_QUADRATIC_TETRA cells reduced to their corners
// leave them: at the midpoint (every seventh off it, as a curved cell's), its scalar near the
// average of the ends. Coded on their edges, the nodes cost a fraction of what they cost as unused
// points after the level, and the decoder emits them while it peels.
TEST(LevelCodecReal, MidEdgeNodesAreCodedOnTheirEdges) {
  TetMesh m = importOrDie({{"vtk/spx.vtk"}, 6, 2.04});
  ASSERT_EQ(m.coord_type, ScalarType::kFloat32);
  ASSERT_EQ(m.point_fields.size(), 1u);
  const std::set<std::pair<uint32_t, uint32_t>> edges = test::tetEdges(m);
  const size_t corners = m.numPoints();
  Field scalars = m.point_fields[0];
  scalars.bytes.resize((corners + edges.size()) * sizeof(float));
  size_t k = corners;
  for (const auto& [a, b] : edges) {
    const double bend = k % 7 == 0 ? 0.01 : 0.0;
    for (int i = 0; i < 3; ++i)
      m.coords.push_back(static_cast<float>((m.point(a)[i] + m.point(b)[i]) * 0.5 +
                                            bend * (m.point(b)[(i + 1) % 3] - m.point(a)[(i + 1) % 3])));
    scalars.set<float>(
        k, 0,
        static_cast<float>(0.5 * (scalars.get(a, 0) + scalars.get(b, 0)) * (1.0 + 0.001 * static_cast<double>(k % 5))));
    ++k;
  }
  m.point_fields[0] = scalars;
  ASSERT_TRUE(m.checkConsistency("spx with mid-edge nodes").isOk());

  auto values = [](const EncodedLevel& e) { return e.geometry.size() + e.point_fields[0].size(); };
  const EncodedLevel on = test::roundTrip(m);
  EncodeOptions off_options;
  off_options.edge_points = false;
  const EncodedLevel off = test::roundTrip(m, nullptr, off_options);
  EXPECT_LT(values(on), values(off) / 2) << "edge points " << values(on) << " bytes, as unused points " << values(off);
  EXPECT_LT(values(on), xzOfRawArrays(m, "spx_mid_edge") / 2);

  // The nodes come while the tetrahedra do: between the first tetrahedron and the last, each vertex
  // event retired by the very next event.
  struct OrderSink : test::CheckingSink {
    Status tet(const uint32_t v[4], const uint8_t* cells) override {
      ++tets;
      last_vertex = ~0u;
      return CheckingSink::tet(v, cells);
    }
    Status vertex(uint32_t id, const double xyz[3], const uint8_t* values) override {
      last_vertex = id;
      return CheckingSink::vertex(id, xyz, values);
    }
    Status retireVertex(uint32_t id) override {
      if (id == last_vertex && tets > 0 && tets < total) ++retired_at_once;
      last_vertex = ~0u;
      return CheckingSink::retireVertex(id);
    }
    uint64_t tets = 0, total = 0, retired_at_once = 0;
    uint32_t last_vertex = ~0u;
  } sink;
  sink.total = m.numTets();
  ASSERT_TRUE(decodeLevel(on.header, payloadOf(on), sink, nullptr, "spx with mid-edge nodes").isOk());
  EXPECT_EQ(sink.retired_at_once, edges.size());
}

// Ossicles is a thin shell (3412 boundary triangles for 5058 tetrahedra, nearly every point on the
// boundary): the boundary surface costs about 0.6 bit per tetrahedron, and many apexes lie across
// the shell, outside the front fans (ranked escapes, spec 10.4, reach them). The hardest dataset:
// it is a Delaunay mesh, and ranked by the Delaunay sweep first it takes about 1.4 bits.
TEST(LevelCodecReal, VtuThinShellOssicles) { checkCase({{"vtu/Ossicles.vtu"}, 6, 1.6}); }

TEST(LevelCodecReal, MeditBunny) { checkCase({{"medit/bunny.mesh"}, 6, 2.04}); }

}  // namespace
}  // namespace gtn
