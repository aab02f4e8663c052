// Tests of the renderers: the streaming (integrated) renderer against the generic one, the physics of
// the opacity model, robustness to zero-volume cells and unwelded seams, and the memory it holds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>
#include <unordered_map>

#include "codec/level_codec.h"
#include "convert/import.h"
#include "mesh/faces.h"
#include "mesh/hex_split.h"
#include "mesh/index.h"
#include "mesh/mesh_stats.h"
#include "mesh/mesh_stream.h"
#include "render/generic_renderer.h"
#include "render/stream_renderer.h"
#include "test_util.h"

namespace gtn {
namespace {

// A test-only stand-in for the decoder: streams a mesh in the mesh-stream order (boundary surface
// first, then tetrahedra breadth-first from the boundary), retiring each vertex after its last
// tetrahedron. Reports the largest number of live vertices.
Status streamMesh(const TetMesh& mesh, MeshSink& sink, uint64_t* peak_live = nullptr) {
  const FaceAdjacency adj = computeFaceAdjacency(mesh);
  const std::vector<Triangle> boundary = boundaryTriangles(mesh, adj);
  LevelHeader header;
  header.points = mesh.numPoints();
  header.tets = mesh.numTets();
  header.boundary_triangles = boundary.size();
  header.coord_type = mesh.coord_type;
  for (const Field& f : mesh.point_fields) header.point_fields.push_back({f.name, f.components, f.type});
  for (int i = 0; i < 3; ++i) header.bbox_min[i] = 1e300, header.bbox_max[i] = -1e300;
  for (size_t v = 0; v < mesh.numPoints(); ++v)
    for (int i = 0; i < 3; ++i) {
      header.bbox_min[i] = std::min(header.bbox_min[i], mesh.point(v)[i]);
      header.bbox_max[i] = std::max(header.bbox_max[i], mesh.point(v)[i]);
    }
  GTN_RETURN_IF_ERROR(sink.beginLevel(header));
  std::vector<uint32_t> remaining(mesh.numPoints(), 0);
  for (const Tet& t : mesh.tets)
    for (uint32_t v : t) ++remaining[v];
  std::vector<uint32_t> new_id(mesh.numPoints(), kNoIndex);
  uint32_t next = 0;
  uint64_t live = 0, peak = 0;
  std::vector<uint8_t> values;
  auto emit = [&](uint32_t v) -> Status {
    if (new_id[v] != kNoIndex) return Status::ok();
    new_id[v] = next++;
    values.clear();
    for (const Field& f : mesh.point_fields) {
      const size_t n = f.components * f.valueSize();
      values.insert(values.end(), f.bytes.begin() + v * n, f.bytes.begin() + (v + 1) * n);
    }
    peak = std::max(peak, ++live);
    return sink.vertex(new_id[v], mesh.point(v), values.data());
  };
  for (const Triangle& tri : boundary)
    for (uint32_t v : tri) GTN_RETURN_IF_ERROR(emit(v));
  for (const Triangle& tri : boundary) {
    const uint32_t ids[3] = {new_id[tri[0]], new_id[tri[1]], new_id[tri[2]]};
    GTN_RETURN_IF_ERROR(sink.boundaryTriangle(ids));
  }
  GTN_RETURN_IF_ERROR(sink.endBoundary());
  std::vector<char> queued(mesh.numTets(), 0);
  std::deque<uint32_t> queue;
  for (size_t t = 0; t < mesh.numTets(); ++t)
    for (int k = 0; k < 4; ++k)
      if (adj.neighbor[4 * t + k] == kNoNeighbor && !queued[t]) {
        queued[t] = 1;
        queue.push_back(static_cast<uint32_t>(t));
      }
  for (size_t start = 0; start <= mesh.numTets(); ++start) {
    while (!queue.empty()) {
      const uint32_t t = queue.front();
      queue.pop_front();
      for (uint32_t v : mesh.tets[t]) GTN_RETURN_IF_ERROR(emit(v));
      const uint32_t ids[4] = {new_id[mesh.tets[t][0]], new_id[mesh.tets[t][1]], new_id[mesh.tets[t][2]],
                               new_id[mesh.tets[t][3]]};
      GTN_RETURN_IF_ERROR(sink.tet(ids, nullptr));
      for (uint32_t v : mesh.tets[t])
        if (--remaining[v] == 0) {
          --live;
          GTN_RETURN_IF_ERROR(sink.retireVertex(new_id[v]));
        }
      for (int k = 0; k < 4; ++k) {
        const uint32_t n = adj.neighbor[4 * t + k];
        if (n < mesh.numTets() && !queued[n]) {
          queued[n] = 1;
          queue.push_back(n);
        }
      }
    }
    if (start < mesh.numTets() && !queued[start]) {
      queued[start] = 1;
      queue.push_back(static_cast<uint32_t>(start));
    }
  }
  if (peak_live) *peak_live = peak;
  return sink.endLevel();
}

// A structured grid of nx*ny*nz hexahedra, 6 tetrahedra each, with coordinates from `place` and a
// float32 point field "f" from `field`.
TetMesh gridMesh(int nx, int ny, int nz, const std::function<std::array<double, 3>(int, int, int)>& place,
                 const std::function<double(const std::array<double, 3>&)>& field) {
  TetMesh mesh;
  auto id = [&](int i, int j, int k) { return static_cast<uint32_t>((k * (ny + 1) + j) * (nx + 1) + i); };
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        const auto p = place(i, j, k);
        mesh.coords.insert(mesh.coords.end(), p.begin(), p.end());
      }
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const uint32_t h[8] = {id(i, j, k),     id(i + 1, j, k),     id(i + 1, j + 1, k),     id(i, j + 1, k),
                               id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1)};
        splitHexSix(h, mesh.tets);
      }
  Field f("f", 1, ScalarType::kFloat32, mesh.numPoints());
  for (size_t v = 0; v < mesh.numPoints(); ++v)
    f.set<float>(v, 0, static_cast<float>(field({mesh.point(v)[0], mesh.point(v)[1], mesh.point(v)[2]})));
  mesh.point_fields.push_back(std::move(f));
  size_t zero_volume = 0;
  normalizeOrientation(mesh, &zero_volume);
  return mesh;
}

TetMesh unitGrid(int n, const std::function<double(const std::array<double, 3>&)>& field) {
  return gridMesh(
      n, n, n,
      [n](int i, int j, int k) {
        return std::array<double, 3>{1.0 * i / n, 1.0 * j / n, 1.0 * k / n};
      },
      field);
}

double smoothField(const std::array<double, 3>& p) { return std::sin(3 * p[0]) + p[1] * p[1] + 0.5 * p[2]; }

RenderOptions smallOptions(Sampling sampling, Projection projection = Projection::kOrthographic) {
  RenderOptions o;
  o.camera.width = 48;
  o.camera.height = 40;
  o.camera.projection = projection;
  o.sampling = sampling;
  o.transfer = transferPreset("cool-warm").value();
  return o;
}

struct Rendered {
  Image integrated, generic;
  StreamRenderStats stream_stats;
  GenericRenderStats generic_stats;
};

Rendered renderBoth(const TetMesh& mesh, const RenderOptions& options) {
  Rendered r;
  StreamRenderer renderer(options);
  Status st = streamMesh(mesh, renderer);
  EXPECT_TRUE(st.isOk()) << st.message();
  r.integrated = renderer.image();
  r.stream_stats = renderer.stats();
  TetMeshBuilder builder;
  st = streamMesh(mesh, builder);
  EXPECT_TRUE(st.isOk()) << st.message();
  auto image = renderGeneric(builder.header(), builder.mesh(), builder.boundary(), options, &r.generic_stats);
  EXPECT_TRUE(image.isOk()) << image.status().message();
  if (image.isOk()) r.generic = image.value();
  return r;
}

uint64_t litPixels(const Image& image) {
  uint64_t n = 0;
  for (size_t i = 0; i + 2 < image.rgb.size(); i += 3)
    if (image.rgb[i] || image.rgb[i + 1] || image.rgb[i + 2]) ++n;
  return n;
}

void expectSameImage(const Image& a, const Image& b, int tolerance) {
  auto d = compareImages(a, b);
  ASSERT_TRUE(d.isOk());
  EXPECT_LE(d->max_difference, tolerance) << "rmse " << d->rmse << " over " << d->pixels << " pixels";
}

TEST(StreamRenderer, MatchesGenericOnGrid) {
  const TetMesh mesh = unitGrid(6, smoothField);
  for (Sampling sampling : {Sampling::kVolume, Sampling::kFace}) {
    for (Projection projection : {Projection::kOrthographic, Projection::kPerspective}) {
      const Rendered r = renderBoth(mesh, smallOptions(sampling, projection));
      EXPECT_GT(litPixels(r.integrated), 300u);
      expectSameImage(r.integrated, r.generic, 1);
      EXPECT_EQ(r.stream_stats.lost_cursors, 0u);
      EXPECT_EQ(r.generic_stats.lost_cursors, 0u);
      EXPECT_EQ(r.stream_stats.tets, mesh.numTets());
      // Every ray counted for a tetrahedron passed through it: none was left held.
      EXPECT_EQ(r.stream_stats.tets_left_held, 0u);
    }
  }
}

TEST(StreamRenderer, ImageDoesNotDependOnStep) {
  const TetMesh mesh = unitGrid(5, smoothField);
  RenderOptions coarse = smallOptions(Sampling::kVolume);
  coarse.step = 0.01;
  RenderOptions fine = coarse;
  fine.step = 0.0025;
  const Rendered a = renderBoth(mesh, coarse), b = renderBoth(mesh, fine);
  auto d = compareImages(a.integrated, b.integrated);
  ASSERT_TRUE(d.isOk());
  EXPECT_LT(d->rmse, 1.5);
  // Where a ray only clips the volume, a coarse step takes zero or one sample: allow a few such pixels.
  uint64_t off = 0;
  for (size_t i = 0; i < a.integrated.rgb.size(); ++i)
    if (std::abs(a.integrated.rgb[i] - b.integrated.rgb[i]) > 3) ++off;
  EXPECT_LT(off, a.integrated.rgb.size() / 50);
  // Face sampling integrates the same model exactly per cell: close to the fine volume image.
  const Rendered f = renderBoth(mesh, smallOptions(Sampling::kFace));
  auto df = compareImages(f.integrated, b.integrated);
  EXPECT_LT(df->rmse, 3.0);
}

TEST(StreamRenderer, ConstantCubeMatchesAnalyticOpacity) {
  // A unit cube of constant field, seen face-on: the centre ray crosses length 1.
  const TetMesh mesh = unitGrid(3, [](const std::array<double, 3>&) { return 2.0; });
  for (Sampling sampling : {Sampling::kVolume, Sampling::kFace}) {
    RenderOptions o = smallOptions(sampling);
    o.camera.width = o.camera.height = 33;
    o.camera.azimuth = o.camera.elevation = 0;
    o.step = 1e-3;
    o.opacity_unit_distance = 0.5;
    o.transfer = transferPreset("grey").value();
    o.transfer.has_range = true;
    o.transfer.lo = 0;
    o.transfer.hi = 2;  // the value maps to the top: white, opacity 0.6 per 0.5 units
    const Rendered r = renderBoth(mesh, o);
    const double sigma = 0.6 / 0.5;  // VTK's unstructured-grid convention: attenuation o / D
    const double expected = 255.0 * (1 - std::exp(-sigma * 1.0));
    const uint8_t* c = r.integrated.pixel(16, 16);
    EXPECT_NEAR(c[0], expected, 1.0);
    EXPECT_EQ(c[0], c[1]);
    EXPECT_NEAR(r.generic.pixel(16, 16)[0], expected, 1.0);
  }
}

TEST(StreamRenderer, ZeroVolumeLayerLeavesNoArtefact) {
  // The same cube with one layer of cells collapsed to zero thickness (duplicated plane z = 0.5).
  auto field = [](const std::array<double, 3>& p) { return p[0] + 2 * p[1] + 3 * p[2]; };
  const TetMesh plain = gridMesh(
      4, 4, 4,
      [](int i, int j, int k) {
        return std::array<double, 3>{i / 4.0, j / 4.0, k / 4.0};
      },
      field);
  const TetMesh collapsed = gridMesh(
      4, 4, 5,
      [](int i, int j, int k) {
        return std::array<double, 3>{i / 4.0, j / 4.0, (k <= 2 ? k : k - 1) / 4.0};
      },
      field);
  for (Sampling sampling : {Sampling::kVolume, Sampling::kFace}) {
    RenderOptions o = smallOptions(sampling);
    o.camera.azimuth = 20;
    o.camera.elevation = 50;  // rays cross the collapsed layer
    const Rendered a = renderBoth(plain, o), b = renderBoth(collapsed, o);
    expectSameImage(a.integrated, b.integrated, 1);
    expectSameImage(b.integrated, b.generic, 1);
  }
}

TEST(StreamRenderer, UnweldedSeamLeavesNoArtefact) {
  // Two halves of a block with their own (coincident) vertices on the interface: the interface is a
  // pair of coincident boundary sheets of opposite facing.
  auto field = [](const std::array<double, 3>& p) { return p[0] * p[0] + p[1] + p[2]; };
  auto place = [](int i, int j, int k) { return std::array<double, 3>{i / 4.0, j / 4.0, k / 4.0}; };
  const TetMesh whole = gridMesh(8, 4, 4, place, field);
  TetMesh left = gridMesh(4, 4, 4, place, field);
  const TetMesh right = gridMesh(
      4, 4, 4, [&](int i, int j, int k) { return place(i + 4, j, k); }, field);
  const uint32_t offset = static_cast<uint32_t>(left.numPoints());
  left.coords.insert(left.coords.end(), right.coords.begin(), right.coords.end());
  for (Tet t : right.tets) {
    for (uint32_t& v : t) v += offset;
    left.tets.push_back(t);
  }
  left.point_fields[0].bytes.insert(left.point_fields[0].bytes.end(), right.point_fields[0].bytes.begin(),
                                    right.point_fields[0].bytes.end());
  for (Sampling sampling : {Sampling::kVolume, Sampling::kFace}) {
    RenderOptions o = smallOptions(sampling);
    o.camera.azimuth = 70;  // rays cross the seam x = 1
    const Rendered a = renderBoth(whole, o), b = renderBoth(left, o);
    expectSameImage(a.integrated, b.integrated, 2);
    expectSameImage(b.integrated, b.generic, 1);
  }
}

TEST(StreamRenderer, HoldsFarLessThanTheMesh) {
  auto imported = importMesh({test::dataPath("vtk/spx.vtk")}, ImportOptions());
  ASSERT_TRUE(imported.isOk()) << imported.status().message();
  const TetMesh& mesh = imported->mesh;
  RenderOptions o = smallOptions(Sampling::kVolume);
  o.camera.width = o.camera.height = 64;
  const Rendered r = renderBoth(mesh, o);
  EXPECT_GT(litPixels(r.integrated), 500u);
  expectSameImage(r.integrated, r.generic, 1);
  EXPECT_EQ(r.stream_stats.tets, mesh.numTets());
  EXPECT_LT(r.stream_stats.peak_tets_held * 4, mesh.numTets()) << r.stream_stats.peak_tets_held;
  EXPECT_LT(r.stream_stats.peak_vertices, mesh.numPoints());
}

// Streams an encoded mesh through the real level decoder into a sink.
Status decodeInto(const EncodedLevel& enc, MeshSink& sink, DecodeStats* stats) {
  return decodeLevel(enc.header, payloadOf(enc), sink, stats, "test");
}

void checkDecodedRender(const TetMesh& mesh, RenderOptions o, double held_fraction) {
  auto enc = encodeLevel(mesh, EncodeOptions());
  ASSERT_TRUE(enc.isOk()) << enc.status().message();
  TetMeshBuilder builder;
  Status st = decodeInto(enc.value(), builder, nullptr);
  ASSERT_TRUE(st.isOk()) << st.message();
  for (Sampling sampling : {Sampling::kVolume, Sampling::kFace}) {
    o.sampling = sampling;
    StreamRenderer renderer(o);
    DecodeStats stats;
    st = decodeInto(enc.value(), renderer, &stats);
    ASSERT_TRUE(st.isOk()) << st.message();
    GenericRenderStats gstats;
    auto generic = renderGeneric(builder.header(), builder.mesh(), builder.boundary(), o, &gstats);
    ASSERT_TRUE(generic.isOk()) << generic.status().message();
    EXPECT_GT(litPixels(renderer.image()), 500u);
    expectSameImage(renderer.image(), generic.value(), 1);
    const StreamRenderStats& s = renderer.stats();
    EXPECT_EQ(s.tets, mesh.numTets());
    EXPECT_LT(static_cast<double>(s.peak_tets_held), held_fraction * mesh.numTets())
        << s.peak_tets_held << " of " << mesh.numTets();
    EXPECT_LE(s.peak_vertices, stats.peak_live_vertices);
    EXPECT_LE(s.lost_cursors, 2u);
    EXPECT_EQ(s.tets_left_held, 0u);
  }
}

TEST(StreamRenderer, RealDecodeStreamOfSpx) {
  auto imported = importMesh({test::dataPath("vtk/spx.vtk")}, ImportOptions());
  ASSERT_TRUE(imported.isOk()) << imported.status().message();
  RenderOptions o = smallOptions(Sampling::kVolume);
  o.camera.width = o.camera.height = 64;
  checkDecodedRender(imported->mesh, o, 0.3);
}

TEST(StreamRenderer, RealDecodeStreamOfBluntFin) {
  auto imported =
      importMesh({test::dataPath("plot3d/bluntfinxyz.bin"), test::dataPath("plot3d/bluntfinq.bin")}, ImportOptions());
  ASSERT_TRUE(imported.isOk()) << imported.status().message();
  RenderOptions o = smallOptions(Sampling::kVolume);
  o.camera.width = o.camera.height = 64;
  o.field = parseFieldSelector("density").value();
  checkDecodedRender(imported->mesh, o, 0.15);
}

TEST(TransferFunction, ParsesAndRejects) {
  auto tf = parseTransferFunction("# test\nrange -1 1\npoint 0 0 0 0 0\npoint 1 1 0.5 0 0.5  # end\n", "t.tf");
  ASSERT_TRUE(tf.isOk()) << tf.status().message();
  EXPECT_TRUE(tf->has_range);
  double rgb[3], e;
  tf->evaluate(0.0, rgb, &e);
  EXPECT_DOUBLE_EQ(rgb[0], 0.5);
  EXPECT_NEAR(e, 0.25, 1e-12);
  auto bad = parseTransferFunction("point 0 0 0 0 0\npoint 0.5 2 0 0 0\n", "bad.tf");
  ASSERT_FALSE(bad.isOk());
  EXPECT_NE(bad.status().message().find("bad.tf:2"), std::string::npos);
  EXPECT_FALSE(parseTransferFunction("point 0 0 0 0 0\n", "one.tf").isOk());
  EXPECT_FALSE(transferPreset("rainbow").isOk());
  // A UTF-8 byte order mark is skipped; a word that is no directive is shown without raw bytes.
  auto bom = parseTransferFunction("\xEF\xBB\xBFpoint 0 0 0 0 0\npoint 1 1 1 1 1\n", "bom.tf");
  ASSERT_TRUE(bom.isOk()) << bom.status().message();
  EXPECT_EQ(bom->points.size(), 2u);
  auto word = parseTransferFunction("p\xC3\xB6int 0 0 0 0 0\n", "word.tf");
  ASSERT_FALSE(word.isOk());
  EXPECT_NE(word.status().message().find("word.tf:1: unknown directive 'p??int'"), std::string::npos)
      << word.status().message();
  // Positions in a range wider than the largest double: by exact halves.
  TransferFunction wide = *bom;
  wide.lo = -1.5e308;
  wide.hi = 1.5e308;
  EXPECT_EQ(wide.position(0.0), 0.5);
  EXPECT_EQ(wide.position(1.5e308), 1.0);
  EXPECT_EQ(wide.valueAt(0.5), 0.0);
  EXPECT_EQ(wide.valueAt(1.0), 1.5e308);
  EXPECT_EQ(wide.valueAt(0.0), -1.5e308);
  wide.evaluate(1.5e308, rgb, &e);
  EXPECT_EQ(rgb[0], 1.0);
  EXPECT_EQ(e, 1.0);
}

TEST(FieldSelector, ComponentsAndMagnitude) {
  std::vector<FieldDesc> fields = {{"a", 1, ScalarType::kFloat64}, {"v", 3, ScalarType::kFloat32}};
  std::vector<uint8_t> values(8 + 12);
  const double a = 1.5;
  const float v[3] = {3, 4, 12};
  std::memcpy(values.data(), &a, 8);
  std::memcpy(values.data() + 8, v, 12);
  auto mag = ScalarReader::create(fields, parseFieldSelector("v:mag").value());
  ASSERT_TRUE(mag.isOk());
  EXPECT_DOUBLE_EQ(mag->read(values.data()), 13.0);
  auto c2 = ScalarReader::create(fields, parseFieldSelector("v:2").value());
  EXPECT_DOUBLE_EQ(c2->read(values.data()), 12.0);
  auto first = ScalarReader::create(fields, parseFieldSelector("").value());
  EXPECT_DOUBLE_EQ(first->read(values.data()), 1.5);
  EXPECT_FALSE(ScalarReader::create(fields, parseFieldSelector("v:3").value()).isOk());
  EXPECT_FALSE(ScalarReader::create(fields, parseFieldSelector("w").value()).isOk());
  EXPECT_FALSE(ScalarReader::create(fields, parseFieldSelector("v:x").value()).isOk());
  EXPECT_FALSE(parseFieldSelector(":2").isOk());
  // A field whose name holds a colon is selected by that name, first ("a:b" was refused, and "v:2"
  // would be v's component 2 were there no field of that name).
  std::vector<FieldDesc> colons = {
      {"v", 3, ScalarType::kFloat32}, {"a:b", 1, ScalarType::kFloat64}, {"v:2", 1, ScalarType::kFloat64}};
  std::vector<uint8_t> vals(12 + 8 + 8);
  const double ab = 7.25, v2 = -3.5;
  std::memcpy(vals.data(), v, 12);
  std::memcpy(vals.data() + 12, &ab, 8);
  std::memcpy(vals.data() + 20, &v2, 8);
  auto named = ScalarReader::create(colons, parseFieldSelector("a:b").value());
  ASSERT_TRUE(named.isOk()) << named.status().message();
  EXPECT_DOUBLE_EQ(named->read(vals.data()), 7.25);
  auto v2_field = ScalarReader::create(colons, parseFieldSelector("v:2").value());
  ASSERT_TRUE(v2_field.isOk());
  EXPECT_DOUBLE_EQ(v2_field->read(vals.data()), -3.5);
  auto v1 = ScalarReader::create(colons, parseFieldSelector("v:1").value());
  ASSERT_TRUE(v1.isOk());
  EXPECT_DOUBLE_EQ(v1->read(vals.data()), 4.0);
  auto ab_mag = ScalarReader::create(colons, parseFieldSelector("a:b:mag").value());
  ASSERT_TRUE(ab_mag.isOk()) << ab_mag.status().message();
  EXPECT_DOUBLE_EQ(ab_mag->read(vals.data()), 7.25);
}

}  // namespace
}  // namespace gtn
