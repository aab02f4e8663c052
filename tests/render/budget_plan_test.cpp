// The parts of --budget-ms planning without a file or a clock (render/budget_plan.h): the cache
// entry, the levels a calibration times, the cost model and the planner, on calibrations made up
// here whose predictions are worked out by hand.
#include "render/budget_plan.h"

#include <gtest/gtest.h>

#include <cmath>

namespace gtn {
namespace {

// Three stored levels: 1000, 500 and 100 tetrahedra after 0, 200 and 400 merges, each with a tree.
std::vector<BudgetLevel> threeLevels() { return {{1000, 0, true}, {500, 200, true}, {100, 400, true}}; }

// Levels 0 and 2 timed (in the order measured: level 0 first): whole runs 100 and 10 ms, decoding 10
// and 1 ms; the floor is level 2 with 50 merges, 20 tetrahedra, 4 ms.
BudgetCalibration calibration() {
  BudgetCalibration c;
  c.points = {{1000, 100}, {100, 10}};
  c.decode_points = {{1000, 10}, {100, 1}};
  c.floor_merges = 50;
  c.floor_tets = 20;
  c.floor_ms = 4;
  return c;
}

TEST(BudgetPlan, InterpolationIsLinearInTheTetrahedraOrInTheirLogarithm) {
  EXPECT_DOUBLE_EQ(interpolateCost({{0, 0}, {10, 10}}, 5, false), 5);
  EXPECT_DOUBLE_EQ(interpolateCost({{0, 0}, {10, 10}}, 20, false), 20);  // beyond: the last slope
  EXPECT_DOUBLE_EQ(interpolateCost({{0, 10}, {10, 5}}, 5, false), 10);   // never decreasing
  EXPECT_DOUBLE_EQ(interpolateCost({{10, 20}}, 5, false), 10);           // one point: proportional
  EXPECT_NEAR(interpolateCost({{10, 1}, {100, 2}}, 1000, true), 3, 1e-12);
  EXPECT_NEAR(interpolateCost({{10, 1}, {100, 2}, {1000, 5}}, 500, true), 2 + 3 * std::log10(5.0), 1e-12);
  EXPECT_EQ(interpolateCost({}, 5, true), 0);
}

TEST(BudgetPlan, CalibrationTimesTheCoarsestTheSixteenthTheQuarterAndLevelZero) {
  std::vector<BudgetLevel> levels;
  for (uint64_t tets : {8000, 4000, 2000, 1000, 500, 250}) levels.push_back({tets, 0, true});
  EXPECT_EQ(levelsToTime(levels), (std::vector<size_t>{0, 2, 4, 5}));
  // Every level from the sixteenth to the coarsest.
  levels.clear();
  for (uint64_t tets : {8000, 300, 200, 100}) levels.push_back({tets, 0, true});
  EXPECT_EQ(levelsToTime(levels), (std::vector<size_t>{0, 1, 2, 3}));
  EXPECT_EQ(levelsToTime({{100, 0, false}}), (std::vector<size_t>{0}));
}

TEST(BudgetPlan, TheCacheEntryRoundTripsAndBadEntriesReadAsNothing) {
  BudgetCalibration c = calibration();
  c.offset = 3.5;
  nlohmann::json entry = calibrationToJson(c);
  EXPECT_EQ(entry["tets"], nlohmann::json({1000.0, 100.0}));
  EXPECT_EQ(entry["decode_ms"], nlohmann::json({10.0, 1.0}));
  EXPECT_EQ(entry["floor"]["merges"], 50.0);
  EXPECT_FALSE(entry.contains("spread_ms"));
  entry["spread_ms"] = 2.0;
  const BudgetCalibration back = calibrationFromJson(&entry);
  EXPECT_EQ(back.points, c.points);
  EXPECT_EQ(back.decode_points, c.decode_points);
  EXPECT_EQ(back.floor_merges, 50);
  EXPECT_EQ(back.floor_tets, 20);
  EXPECT_EQ(back.floor_ms, 4);
  EXPECT_EQ(back.offset, 3.5);
  EXPECT_EQ(back.spread, 2.0);
  // No floor: null.
  c.floor_merges = 0;
  const nlohmann::json no_floor = calibrationToJson(c);
  EXPECT_TRUE(no_floor["floor"].is_null());
  EXPECT_EQ(calibrationFromJson(&no_floor).floor_merges, 0);

  EXPECT_TRUE(calibrationFromJson(nullptr).points.empty());
  auto broken = [&](auto&& edit) {
    nlohmann::json e = entry;
    edit(e);
    return calibrationFromJson(&e);
  };
  EXPECT_TRUE(broken([](nlohmann::json& e) { e["ms"][1] = "fast"; }).points.empty());
  EXPECT_TRUE(broken([](nlohmann::json& e) { e["ms"].push_back(1.0); }).points.empty());
  EXPECT_TRUE(broken([](nlohmann::json& e) { e.erase("decode_ms"); }).points.empty());  // an older entry
  EXPECT_TRUE(broken([](nlohmann::json& e) { e["decode_ms"][0] = nullptr; }).points.empty());
  EXPECT_TRUE(broken([](nlohmann::json& e) { e = nlohmann::json::array(); }).points.empty());
  // A stale offset or spread reads as none; a floor without its time as no floor.
  EXPECT_EQ(broken([](nlohmann::json& e) { e["offset_ms"] = 2500.0; }).offset, 0);
  EXPECT_EQ(broken([](nlohmann::json& e) { e["offset_ms"] = -20.0; }).offset, -20);
  EXPECT_EQ(broken([](nlohmann::json& e) { e["spread_ms"] = -1.0; }).spread, 0);
  EXPECT_EQ(broken([](nlohmann::json& e) { e["floor"].erase("ms"); }).floor_merges, 0);
}

TEST(BudgetPlan, ACalibrationMustNameTheFilesLevels) {
  EXPECT_TRUE(calibrationNamesLevels(calibration(), threeLevels()));
  BudgetCalibration other = calibration();
  other.points[1].first = 99;
  EXPECT_FALSE(calibrationNamesLevels(other, threeLevels()));
}

TEST(BudgetPlan, TheCostModelPredictsStoredMergedAndFloorPlans) {
  BudgetCalibration c = calibration();
  c.offset = 2;
  const BudgetCostModel model(c, threeLevels());
  EXPECT_EQ(model.calibration().points.front().first, 100);  // sorted
  EXPECT_NEAR(model.whole(500), 10 + 90 * std::log10(5.0), 1e-9);
  EXPECT_NEAR(model.decoding(500), 5, 1e-9);
  EXPECT_NEAR(model.stored(0), 102, 1e-9);
  EXPECT_NEAR(model.stored(2), 12, 1e-9);
  EXPECT_TRUE(model.timed(1000));
  EXPECT_FALSE(model.timed(500));
  // Level 0 with every merge to level 1: decoding level 0 (and 5%), then a run of 500 tetrahedra
  // less its decoding.
  EXPECT_NEAR(model.merged(0, 1.0), 2 + 1.05 * 10 + (10 + 90 * std::log10(5.0)) - 5, 1e-9);
  EXPECT_NEAR(model.merged(0, 0.0), 2 + 1.05 * 10 + 100 - 10, 1e-9);
  ASSERT_TRUE(model.hasFloor());
  EXPECT_NEAR(model.floor(1.0), 2 + 4, 1e-9);
  EXPECT_NEAR(model.floor(0.0), 2 + 10, 1e-9);
  // No floor: too many tetrahedra left, or no tree on the coarsest level.
  BudgetCalibration big = calibration();
  big.floor_tets = 100;
  EXPECT_FALSE(BudgetCostModel(big, threeLevels()).hasFloor());
  std::vector<BudgetLevel> no_tree = threeLevels();
  no_tree.back().has_tree = false;
  EXPECT_FALSE(BudgetCostModel(calibration(), no_tree).hasFloor());
}

TEST(BudgetPlan, FewestMergesFittingIsTheFirstCountThatFits) {
  auto line = [](double f) { return 100 - 80 * f; };  // fits 50 from f = 0.625
  EXPECT_EQ(fewestMergesFitting(8, 50, line), 5u);
  EXPECT_EQ(fewestMergesFitting(7, 50, line), 5u);  // ceil(0.625 * 7)
  EXPECT_EQ(fewestMergesFitting(8, 10, line), std::nullopt);
  EXPECT_EQ(fewestMergesFitting(0, 50, line), std::nullopt);
  EXPECT_EQ(fewestMergesFitting(8, 200, line), 1u);  // at least one merge
}

TEST(BudgetPlan, ThePlannerTakesTheFinestPlanThatFitsEightyPercent) {
  const BudgetCostModel model(calibration(), threeLevels());
  // Level 0 as it is (100 ms <= 80% of 200).
  BudgetPlan p = planForBudget(model, 200);
  EXPECT_EQ(p.choice.level, 0);
  EXPECT_EQ(p.choice.merges, -1);
  EXPECT_EQ(p.extra, 0u);
  EXPECT_NEAR(p.predicted, 100, 1e-9);
  // Aim 80: level 0 with the fewest merges towards level 1 that fit (level 1 was not timed).
  p = planForBudget(model, 100);
  EXPECT_EQ(p.choice.level, -1);
  EXPECT_EQ(p.level, 0u);
  ASSERT_GE(p.extra, 1u);
  ASSERT_LE(p.extra, 200u);
  EXPECT_EQ(p.choice.merges, static_cast<int64_t>(p.extra));
  EXPECT_LE(p.predicted, 80);
  EXPECT_NEAR(p.predicted, model.merged(0, p.extra / 200.0), 1e-12);
  EXPECT_GT(model.merged(0, (p.extra - 1) / 200.0), 80);
  // Aim 40: level 1 with merges towards level 2.
  p = planForBudget(model, 50);
  EXPECT_EQ(p.level, 1u);
  EXPECT_EQ(p.choice.merges, static_cast<int64_t>(200 + p.extra));
  EXPECT_LE(p.predicted, 40);
  EXPECT_GT(model.merged(1, (p.extra - 1) / 200.0), 40);
  // Aim 10: the coarsest level as it is.
  p = planForBudget(model, 12.5);
  EXPECT_EQ(p.choice.level, 2);
  EXPECT_NEAR(p.predicted, 10, 1e-9);
  // Aim 8: the coarsest level with some of its floor's merges.
  p = planForBudget(model, 10);
  EXPECT_EQ(p.level, 2u);
  EXPECT_EQ(p.choice.merges, static_cast<int64_t>(400 + p.extra));
  EXPECT_LT(p.extra, 50u);
  EXPECT_LE(p.predicted, 8);
  // Nothing fits: the whole floor, predicted beyond the budget.
  p = planForBudget(model, 1);
  EXPECT_EQ(p.level, 2u);
  EXPECT_EQ(p.extra, 50u);
  EXPECT_EQ(p.choice.merges, 450);
  EXPECT_NEAR(p.predicted, 4, 1e-9);
  // Without a floor, the coarsest level as it is.
  BudgetCalibration no_floor = calibration();
  no_floor.floor_merges = 0;
  p = planForBudget(BudgetCostModel(no_floor, threeLevels()), 1);
  EXPECT_EQ(p.choice.level, 2);
  EXPECT_NEAR(p.predicted, 10, 1e-9);
}

TEST(BudgetPlan, TheSpreadAndTimedLevelsChangeThePlan) {
  // A spread of 20 ms keeps 30 ms of room: aim 70 rather than 80, which level 0 with merges misses.
  BudgetCalibration spread = calibration();
  spread.spread = 20;
  BudgetPlan p = planForBudget(BudgetCostModel(spread, threeLevels()), 100);
  EXPECT_EQ(p.level, 1u);
  EXPECT_LE(p.predicted, 70);
  // Level 1 timed too: between two timed levels the next level is the plan, not merges.
  BudgetCalibration all = calibration();
  all.points.push_back({500, 60});
  all.decode_points.push_back({500, 5});
  p = planForBudget(BudgetCostModel(all, threeLevels()), 100);
  EXPECT_EQ(p.choice.level, 1);
  EXPECT_NEAR(p.predicted, 60, 1e-9);
}

TEST(BudgetPlan, TheModelIsDescribedWithItsFloor) {
  EXPECT_EQ(describeBudgetModel(BudgetCostModel(calibration(), threeLevels())),
            "100 tets 10.0 ms (decoding 1.0), 1000 tets 100.0 ms (decoding 10.0), level 2 with 50 merges of its tree "
            "20 tets 4.0 ms");
}

}  // namespace
}  // namespace gtn
