// The apex candidates of a gate face (spec section 10.4): the front vertices on the fans around the
// gate's edges, by multiplicity then distance to the predicted apex; those on the wrong side of the
// gate dropped; the symbol of a vertex and the vertex of a symbol agree; and the context.
#include "codec/candidates.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "codec/front.h"

namespace gtn::level {
namespace {

// A gate face (0, 1, 2) in the plane z = 0 with an open face across each of its edges, whose third
// vertices 5, 3 and 4 are each reached by two fan walks; slot 6 is live but on no fan.
struct Scene {
  SlotPool pool;
  Front front;
  long gate = -1;
  explicit Scene(double z3, uint32_t d) {
    const double pos[7][3] = {{0, 0, 0},       {1, 0, 0},        {0, 1, 0},     {0.5, -0.5, z3},
                              {0.7, 0.7, 0.2}, {-0.5, 0.5, 0.9}, {0.3, 0.3, -1}};
    for (int s = 0; s < 7; ++s) {
      pool.alloc();
      for (int i = 0; i < 3; ++i) pool.position(s)[i] = pos[s][i];
    }
    const uint32_t g[3] = {0, 1, 2}, f5[3] = {0, 2, 5}, f3[3] = {1, 0, 3}, f4[3] = {2, 1, 4};
    gate = front.open(g, d, kNoIndex, pool);
    front.open(f5, kNoIndex, kNoIndex, pool);
    front.open(f3, kNoIndex, kNoIndex, pool);
    front.open(f4, kNoIndex, kNoIndex, pool);
  }
};

TEST(ApexCandidates, RankByMultiplicityThenDistanceToThePrediction) {
  Scene scene(0.3, kNoIndex);
  ApexCandidates cands(scene.pool, scene.front.edges);
  const FrontFace& g = scene.front.faces.at(scene.gate);
  const Orient3dFilter side(scene.pool.position(0), scene.pool.position(1), scene.pool.position(2));
  const double p[3] = {0.3, 0.3, 0.5};
  const uint32_t ctx = cands.gather(g, side, p);
  // Squared distances to p: 4 0.41, 3 0.72, 5 0.84.
  EXPECT_EQ(cands.candidateAt(0), 4u);
  EXPECT_EQ(cands.candidateAt(1), 3u);
  EXPECT_EQ(cands.candidateAt(2), 5u);
  EXPECT_EQ(cands.candidateAt(3), kNoIndex);
  EXPECT_EQ(cands.candidateSymbolOf(4), 1u);
  EXPECT_EQ(cands.candidateSymbolOf(5), 3u);
  EXPECT_EQ(cands.candidateSymbolOf(6), kSymEscape);  // live, on no fan
  EXPECT_EQ(cands.candidateSymbolOf(kNoIndex), kSymNew);
  uint32_t ordered[kMaxCandidates];
  ASSERT_EQ(cands.orderedCandidates(ordered), 3);
  EXPECT_EQ(ordered[0], 4u);
  EXPECT_EQ(ordered[1], 3u);
  EXPECT_EQ(ordered[2], 5u);
  // Context: best multiplicity 2 shared by 3 candidates (k = 1 + 3 + 2), the nearest within the
  // mean squared gate edge but not a quarter of it (1), and 4 closes the face across edge (b, c).
  EXPECT_EQ(ctx, ((1u + 3 + 2) * 3 + 1) * 3 + 1);
  EXPECT_EQ(cands.wrongSide(), 0);  // behind a boundary face, before any vote
}

TEST(ApexCandidates, CandidatesOnTheSideOfTheDecodedTetrahedronAreDropped) {
  // Vertex 3 below the gate, on the side of d = 6: it is no candidate (the escape reaches it).
  Scene scene(-0.3, 6);
  ApexCandidates cands(scene.pool, scene.front.edges);
  const FrontFace& g = scene.front.faces.at(scene.gate);
  const Orient3dFilter side(scene.pool.position(0), scene.pool.position(1), scene.pool.position(2));
  const double p[3] = {0.3, 0.3, 0.5};
  cands.gather(g, side, p);
  EXPECT_NE(cands.wrongSide(), 0);
  EXPECT_EQ(cands.candidateSymbolOf(3), kSymEscape);
  EXPECT_EQ(cands.candidateAt(0), 4u);
  EXPECT_EQ(cands.candidateAt(1), 5u);
  EXPECT_EQ(cands.candidateAt(2), kNoIndex);
  // The sweep of the gate face: its circumcircle's centre (0.5, 0.5, 0) and squared radius 0.5.
  cands.ensureSweep();
  EXPECT_DOUBLE_EQ(cands.sweepCentre()[0], 0.5);
  EXPECT_DOUBLE_EQ(cands.sweepCentre()[1], 0.5);
  EXPECT_DOUBLE_EQ(cands.sweepRadius2(), 0.5);
  // Keys: the sweep parameter at which the sphere through the gate's corners, moving away from d,
  // meets a point, in 1/64 of the circumradius, rounded down: (|q - c|^2 - r^2) / (2 h) for a point at
  // height h above the centre c.
  const double up1[3] = {0.5, 0.5, 1}, up2[3] = {0.5, 0.5, 2}, below[3] = {0.5, 0.5, -1};
  EXPECT_EQ(cands.sweepKey(up1), std::floor(0.25 * 64 / std::sqrt(0.5)));   // 22
  EXPECT_EQ(cands.sweepKey(up2), std::floor(0.875 * 64 / std::sqrt(0.5)));  // 79
  EXPECT_EQ(cands.sweepKey(below), 1e18);                                   // never met
}

}  // namespace
}  // namespace gtn::level
