// The prediction rules of spec section 10.5: the rules' weights, the interpolation weights that
// reproduce a linear field, the apex prediction, and the encoder's residual costs (the four-at-a-time
// float32 path gives what the plain one gives).
#include "codec/prediction.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

namespace gtn::level {
namespace {

TEST(Prediction, RulesWeighTheStencilAsTheSpecSays) {
  const double x[4] = {1.5, 10.0, 100.0, 1000.0};  // a, b, c, d
  EXPECT_EQ(kWeightedRule[0](x), 0.0);
  EXPECT_EQ(kWeightedRule[1](x), 1.5 + 10 - 1000);  // a + b - d
  EXPECT_EQ(kWeightedRule[4](x), 1.5 + 10 - 100);   // a + b - c
  EXPECT_EQ(kWeightedRule[7](x), 1.5 + 10 + 100 - 2000);
  EXPECT_EQ(kWeightedRule[12](x), 1000.0);  // copies d
  double all[kRules];
  weightedRules(x, all, std::make_integer_sequence<uint32_t, kRules>());
  for (uint32_t r = 0; r < kRules; ++r) EXPECT_EQ(all[r], kWeightedRule[r](x)) << r;
  // Rules that read d need it.
  EXPECT_TRUE(ruleAllowed(4, false, kCoordRules));
  EXPECT_FALSE(ruleAllowed(1, false, kCoordRules));
  EXPECT_TRUE(ruleAllowed(1, true, kCoordRules));
  EXPECT_FALSE(ruleAllowed(9, true, kCoordRules));  // beyond the coordinate rules
  // The previous choice is tried first, then the others in order.
  EXPECT_EQ(triedRule(0, 5), 5u);
  EXPECT_EQ(triedRule(1, 5), 0u);
  EXPECT_EQ(triedRule(5, 5), 4u);
  EXPECT_EQ(triedRule(6, 5), 6u);
}

TEST(Prediction, InterpolationWeightsReproduceALinearField) {
  const double a[3] = {0, 0, 0}, b[3] = {2, 0, 0}, c[3] = {0, 3, 0}, d[3] = {0, 0, 4};
  const double* s[4] = {a, b, c, d};
  auto field = [](const double* p) { return 3 + 2 * p[0] - p[1] + 0.5 * p[2]; };
  const double x[3] = {0.7, 0.4, 1.9};
  double lambda[4];
  ASSERT_EQ(stencilWeights(FieldPrediction::kInterpolate, s, x, lambda), 4);
  double v = 0;
  for (int j = 0; j < 4; ++j) v += lambda[j] * field(s[j]);
  EXPECT_NEAR(v, field(x), 1e-12);
  // Far outside the tetrahedron (a weight beyond 8): the average of a, b and c instead.
  const double far[3] = {50, 0, 0};
  ASSERT_EQ(stencilWeights(FieldPrediction::kInterpolate, s, far, lambda), 3);
  EXPECT_DOUBLE_EQ(lambda[0], 1.0 / 3);
  // A flat stencil: the average too.
  const double* flat[4] = {a, b, c, a};
  EXPECT_EQ(stencilWeights(FieldPrediction::kInterpolate, flat, x, lambda), 3);
  EXPECT_EQ(stencilWeights(FieldPrediction::kParallelogram, s, x, lambda), 3);
  EXPECT_EQ(lambda[2], -1.0);
  EXPECT_EQ(stencilWeights(FieldPrediction::kEdge, s, x, lambda), 2);
  EXPECT_EQ(lambda[1], 0.5);
  EXPECT_EQ(stencilWeights(FieldPrediction::kLast, s, x, lambda), 0);
}

TEST(Prediction, TheApexLiesBeyondTheFaceAwayFromD) {
  const double a[3] = {0, 0, 0}, b[3] = {3, 0, 0}, c[3] = {0, 3, 0}, d[3] = {1, 1, -3};
  double p[3];
  predictApex(a, b, c, d, p);
  // g + 0.6 (g - d), g = (1, 1, 0).
  EXPECT_DOUBLE_EQ(p[0], 1.0);
  EXPECT_DOUBLE_EQ(p[1], 1.0);
  EXPECT_DOUBLE_EQ(p[2], 1.8);
  // Behind a boundary face: along the normal (b - a) x (c - a) = +z, by 0.8 of the mean edge.
  predictApex(a, b, c, nullptr, p);
  const double edge = (3 + 3 + 3 * std::sqrt(2.0)) / 3;
  EXPECT_NEAR(p[2], 0.8 * edge, 1e-12);
  EXPECT_DOUBLE_EQ(p[0], 1.0);
}

TEST(Prediction, RuleCostsAreSixteenTimesTheResidualBitLength) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1000, 1000);
  for (int trial = 0; trial < 200; ++trial) {
    double v[8];
    for (double& x : v) x = u(rng);
    if (trial % 7 == 0) v[3] = std::nan("");  // non-finite predictions count as 0
    if (trial % 11 == 0) v[5] = 1e300;
    const float actual = static_cast<float>(u(rng));
    uint8_t raw[4];
    std::memcpy(raw, &actual, 4);
    const uint64_t key = keyFromRaw(ScalarType::kFloat32, raw);
    int fast[8] = {}, plain[8] = {};
    addRuleCosts<8>(std::integral_constant<ScalarType, ScalarType::kFloat32>(), key, v, fast);
    addRuleCosts<8>(ScalarType::kFloat32, key, v, plain);
    for (int r = 0; r < 8; ++r) {
      EXPECT_EQ(fast[r], plain[r]) << trial << " " << r;
      EXPECT_EQ(plain[r], 16 * residualBits(key, keyFromPrediction(ScalarType::kFloat32, v[r]), keyMask(32)));
    }
  }
  // An exact prediction costs nothing.
  int cost[4] = {};
  const double exact[4] = {2.5, 2.5, 2.5, 2.5};
  uint8_t raw[4];
  const float f = 2.5f;
  std::memcpy(raw, &f, 4);
  addRuleCosts<4>(ScalarType::kFloat32, keyFromRaw(ScalarType::kFloat32, raw), exact, cost);
  EXPECT_EQ(cost[0], 0);
}

}  // namespace
}  // namespace gtn::level
