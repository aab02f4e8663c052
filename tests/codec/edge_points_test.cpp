// findEdgePoints: which unused points the encoder codes on an edge (spec section 10.5).
#include "codec/edge_points.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <set>

#include "codec_test_util.h"

namespace gtn {
namespace {

// Two tetrahedra sharing the face (1, 2, 3), and unused points placed around their edges.
TetMesh twoTets() {
  TetMesh m;
  m.coords = {0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0, 2, 2, 2, 2};
  m.tets = {{0, 1, 2, 3}, {1, 2, 3, 4}};
  return m;
}

uint32_t addPoint(TetMesh& m, double x, double y, double z) {
  m.coords.insert(m.coords.end(), {x, y, z});
  return static_cast<uint32_t>(m.numPoints() - 1);
}

TEST(EdgePoints, MidpointsAndNearbyPointsGoToTheirEdge) {
  TetMesh m = twoTets();
  const uint32_t mid01 = addPoint(m, 1, 0, 0);
  const uint32_t bent23 = addPoint(m, 0, 1.1, 1.2);  // 0.08 of the edge's length off its midpoint
  const uint32_t far = addPoint(m, 0.4, 0, 0);       // 0.3 of (0, 1)'s length off its midpoint
  const uint32_t outside = addPoint(m, 9, 9, 9);
  const uint32_t mid14 = addPoint(m, 2, 1, 1);
  const std::vector<EdgePoint> found = findEdgePoints(m);
  ASSERT_EQ(found.size(), 3u);
  EXPECT_EQ(found[0].point, mid01);
  EXPECT_EQ(found[0].a, 0u);
  EXPECT_EQ(found[0].b, 1u);
  EXPECT_EQ(found[1].point, bent23);
  EXPECT_EQ(found[1].a, 2u);
  EXPECT_EQ(found[1].b, 3u);
  EXPECT_EQ(found[2].point, mid14);
  EXPECT_EQ(found[2].a, 1u);
  EXPECT_EQ(found[2].b, 4u);
  for (const EdgePoint& e : found) {
    EXPECT_NE(e.point, far);
    EXPECT_NE(e.point, outside);
  }
}

TEST(EdgePoints, NoneWithoutUnusedPointsOrWithNonFiniteOnes) {
  TetMesh m = twoTets();
  EXPECT_TRUE(findEdgePoints(m).empty());
  addPoint(m, std::numeric_limits<double>::quiet_NaN(), 0, 0);
  addPoint(m, 1, std::numeric_limits<double>::infinity(), 0);
  EXPECT_TRUE(findEdgePoints(m).empty());
}

// Thousands of unused points at one spot (placeholders) are not searched from every edge: they stay
// unused points, and the time stays linear.
TEST(EdgePoints, CoincidentPointsAreLeftAlone) {
  TetMesh m;
  m.coords = {0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0, 2, 20, 0, 0, 22, 0, 0, 20, 2, 0, 20, 0, 2};
  m.tets = {{0, 1, 2, 3}, {4, 5, 6, 7}};
  const uint32_t mid01 = addPoint(m, 1, 0, 0);
  for (int i = 0; i < 5000; ++i) addPoint(m, 21, 0, 0);  // the midpoint of (4, 5)
  const std::vector<EdgePoint> found = findEdgePoints(m);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].point, mid01);
}

// The codec round trip of a quadratic grid: every mid-edge node decoded bit for bit, whether the
// encoder codes the nodes on their edges or not, and on their edges for less.
TEST(EdgePoints, QuadraticGridRoundTrips) {
  TetMesh m = test::gridMesh(5, 4, 3, 5);
  test::addFields(m);
  const size_t corners = m.numPoints();
  const std::set<std::pair<uint32_t, uint32_t>> edges = test::tetEdges(m);
  for (const auto& [a, b] : edges)
    for (int i = 0; i < 3; ++i) m.coords.push_back((m.point(a)[i] + m.point(b)[i]) * 0.5);
  for (Field& f : m.point_fields) {
    const size_t item = f.components * f.valueSize();
    f.bytes.resize(m.numPoints() * item);
    size_t v = corners;
    for (const auto& e : edges) std::memcpy(&f.bytes[v++ * item], &f.bytes[e.first * item], item);
  }
  ASSERT_TRUE(m.checkConsistency("quadratic grid").isOk());
  const EncodedLevel on = test::roundTrip(m);
  EncodeOptions off_options;
  off_options.edge_points = false;
  const EncodedLevel off = test::roundTrip(m, nullptr, off_options);
  EXPECT_LT(on.geometry.size(), off.geometry.size() / 2);
}

}  // namespace
}  // namespace gtn
