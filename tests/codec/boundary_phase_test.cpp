// The boundary phase's geometry and loop (spec section 10.3): the corner angle's polynomial arccosine,
// the angle classes of the contexts, and the open loop whose neighbours are the candidates of the
// next triangle, the likelier ear first.
#include "codec/boundary_phase.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

namespace gtn::level {
namespace {

TEST(BoundaryGeometry, CornerAnglesAndTheirClasses) {
  const double o[3] = {0, 0, 0}, x[3] = {2, 0, 0}, y[3] = {0, 3, 0}, xy[3] = {1, 1, 0}, minus_x[3] = {-1, 0, 0};
  EXPECT_NEAR(cornerAngle(o, x, y), M_PI / 2, 1e-4);
  EXPECT_NEAR(cornerAngle(o, x, xy), M_PI / 4, 1e-4);
  EXPECT_NEAR(cornerAngle(o, x, minus_x), M_PI, 1e-4);
  EXPECT_EQ(cornerAngle(o, o, x), 0.0);   // degenerate
  EXPECT_EQ(openingClass(o, x, xy), 0u);  // 45 degrees
  EXPECT_EQ(openingClass(o, x, y), 2u);   // 90: not below
  const double sixty_five[3] = {std::cos(65 * M_PI / 180), std::sin(65 * M_PI / 180), 0};
  EXPECT_EQ(openingClass(o, x, sixty_five), 1u);
  EXPECT_EQ(openingClass(o, o, x), 3u);
  EXPECT_EQ(roomClass(2 * M_PI - 1.0), 0u);  // 57 degrees left
  EXPECT_EQ(roomClass(2 * M_PI - 2.0), 1u);
  EXPECT_EQ(roomClass(M_PI), 2u);
}

// A fan of triangles around vertex 0 in the plane z = 0: 0 at the centre, 1..n on a circle.
struct Fan {
  std::vector<double> pos;
  explicit Fan(int n) {
    pos = {0, 0, 0};
    for (int i = 0; i < n; ++i) {
      const double a = 2 * M_PI * i / n;
      pos.insert(pos.end(), {std::cos(a), std::sin(a), 0});
    }
  }
  const double* operator()(uint32_t s) const { return &pos[3 * size_t{s}]; }
};

TEST(BoundaryLoop, TrianglesCloseTheirSharedHalfEdgesAndTheLoopFollowsTheRim) {
  const Fan fan(6);
  BoundaryLoop loop;
  for (uint32_t s = 0; s < 7; ++s) loop.addSlot(s);
  const uint32_t t1[3] = {0, 1, 2}, t2[3] = {0, 2, 3};
  loop.addTriangle(t1, fan);
  loop.addTriangle(t2, fan);  // closes t1's open half-edge (2, 0)
  EXPECT_NEAR(loop.cornerSum(0), 2 * M_PI / 3, 1e-3);
  EXPECT_EQ(loop.cornerCount(0), 2u);
  EXPECT_EQ(loop.cornerCount(2), 2u);
  // The open loop runs 0 -> 1 -> 2 -> 3 -> 0.
  EXPECT_EQ(loop.next(0), 1u);
  EXPECT_EQ(loop.next(1), 2u);
  EXPECT_EQ(loop.next(2), 3u);
  EXPECT_EQ(loop.next(3), 0u);
  EXPECT_EQ(loop.prev(0), 3u);
  // The queue: t1's (0, 1), (1, 2), (2, 0), then t2's; (2, 0) and (0, 2) are closed.
  std::vector<std::array<uint32_t, 3>> open;
  while (!loop.queueEmpty()) {
    uint32_t p, q, w;
    if (loop.popHalfEdge(&p, &q, &w)) open.push_back({p, q, w});
  }
  const std::vector<std::array<uint32_t, 3>> expected = {{0, 1, 2}, {1, 2, 0}, {2, 3, 0}, {3, 0, 2}};
  EXPECT_EQ(open, expected);
}

TEST(BoundaryLoop, CandidatesWalkTheLoopWithTheFullerEarFirst) {
  const Fan fan(6);
  BoundaryLoop loop;
  for (uint32_t s = 0; s < 7; ++s) loop.addSlot(s);
  // Four of the fan's six triangles around 0: 0 has 240 degrees of corners, little room left.
  for (uint32_t i = 1; i <= 4; ++i) {
    const uint32_t t[3] = {0, i, i + 1};
    loop.addTriangle(t, fan);
  }
  auto live = [](uint32_t s) { return s != 3; };
  // The open half-edge (5, 0) of triangle (0, 4, 5): its ears are next(0) = 1 and prev(5) = 4.
  const BoundaryLoop::Candidates c = loop.candidates(5, 0, 4, fan, live);
  ASSERT_GE(c.n, 2);
  EXPECT_EQ(c.slot[0], 1u);  // the ear at 0, whose corners leave 120 degrees, before the one at 5
  EXPECT_EQ(c.slot[1], 4u);
  for (int i = 0; i < c.n; ++i) EXPECT_NE(c.slot[i], 3u);  // not live
  // Context: the loop does not close; the triangle (0, 5, 1) would open 120 degrees at 0 (class 2),
  // 120 degrees are left there (room class 1), and 0 has four triangles.
  EXPECT_EQ(c.context, (2u * 4 + 1) * 2 + 1);
  loop.release();
  EXPECT_TRUE(loop.done());
}

}  // namespace
}  // namespace gtn::level
