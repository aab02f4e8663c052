// The parts of chooseForBudget (render/time_budget.h) that do not touch the file or the clock: the
// calibration as the cache stores it, which levels a calibration times, the cost model built from a
// calibration, and the planner that picks the finest plan that fits a budget under that model.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "render/render_input.h"

namespace gtn {

// Bound of the learnt offset and spread: beyond it the calibration is stale, not the run slower.
inline constexpr double kMaxBudgetOffsetMs = 2000.0;

// What planning needs of one stored level.
struct BudgetLevel {
  uint64_t tets = 0;
  uint64_t merges = 0;    // merges of the level-0 tree already applied in it
  bool has_tree = false;  // a merge tree to simplify it further on the fly
};

// What a calibration measured, and what runs since have taught (time_budget.h).
struct BudgetCalibration {
  // Measured (tetrahedra, ms) points, in the order measured: whole runs, and decoding alone (the
  // same tetrahedra, index by index). Empty: nothing usable, calibrate.
  std::vector<std::pair<double, double>> points, decode_points;
  // The floor: the coarsest level with `floor_merges` merges of its tree applied on the fly, the
  // tetrahedra then rendered and the time of the run; floor_merges 0 when there is none.
  double floor_merges = 0, floor_tets = 0, floor_ms = 0;
  double offset = 0;  // added to every prediction: what a real run costs beyond the calibration
  double spread = 0;  // how far runs scatter around the predictions: the room a plan keeps
};

// The calibration of a cache entry; empty points when `entry` is null, malformed or older (no
// decoding times). An offset or spread outside [-kMaxBudgetOffsetMs, kMaxBudgetOffsetMs] (the spread
// also below 0) reads as 0.
BudgetCalibration calibrationFromJson(const nlohmann::json* entry);
// The cache entry of a fresh calibration (the floor null when there is none; no spread yet).
nlohmann::json calibrationToJson(const BudgetCalibration& calibration);

// Whether `calibration` names only tetrahedra counts of the file's `levels` (a calibration of another
// file under the same key is made again, not planned with).
bool calibrationNamesLevels(const BudgetCalibration& calibration, const std::vector<BudgetLevel>& levels);

// The levels a calibration times, ascending: the coarsest, the finest with at most a sixteenth of
// level 0's tetrahedra and every level from there to the coarsest, the finest with at most a quarter,
// and level 0, so that every level's time is interpolated, not extrapolated.
std::vector<size_t> levelsToTime(const std::vector<BudgetLevel>& levels);

// Interpolation through (x, y) points sorted by x, linear in x or in log x; beyond them, the nearest
// segment's slope (never decreasing); one point: proportional to x.
double interpolateCost(const std::vector<std::pair<double, double>>& points, double n, bool logarithmic);

// The predicted time of each plan (ms), from a calibration and the file's levels (at least one).
class BudgetCostModel {
 public:
  BudgetCostModel(BudgetCalibration calibration, std::vector<BudgetLevel> levels);

  const BudgetCalibration& calibration() const { return calibration_; }  // points sorted by tetrahedra
  const std::vector<BudgetLevel>& levels() const { return levels_; }
  // A whole run of n tetrahedra, without the offset: interpolated in the logarithm of the tetrahedra.
  double whole(double n) const;
  // Decoding n tetrahedra alone: linear in them, never more than the whole run.
  double decoding(double n) const;
  // Whether a level of `tets` tetrahedra was timed.
  bool timed(uint64_t tets) const;
  // Stored level i as it is.
  double stored(size_t i) const;
  // Level i with `fraction` of the merges to level i + 1 on the fly: decoding level i in full (plus
  // 5% for the filter) and the rest of a run of the tetrahedra left.
  double merged(size_t i, double fraction) const;
  // Whether the coarsest level has a usable floor, and the coarsest level with `fraction` of the
  // floor's merges on the fly (interpolated in the logarithm of the tetrahedra left).
  bool hasFloor() const { return has_floor_; }
  double floor(double fraction) const;

 private:
  BudgetCalibration calibration_;
  std::vector<BudgetLevel> levels_;
  bool has_floor_ = false;
};

// The fewest of `span` merges whose prediction `at(merges / span)` fits `aim`, by bisection (the
// prediction falls with the merges, up to the interpolation's kinks), at least 1; nothing when even
// all of them do not fit or span is 0.
std::optional<uint64_t> fewestMergesFitting(uint64_t span, double aim, const std::function<double(double)>& at);

struct BudgetPlan {
  LevelChoice choice;    // what to render
  size_t level = 0;      // the stored level decoded
  uint64_t extra = 0;    // merges on the fly on top of it
  double predicted = 0;  // ms
};

// The finest plan predicted to fit `available_ms`, aiming at 80% of it (and 1.5 spreads below it): a
// stored level as is, else that level with the fewest on the fly merges towards the next level that
// fit (not between two timed levels), else the next level; below the coarsest level its floor's
// merges. When nothing fits: the cheapest plan, the whole floor (else the coarsest level).
BudgetPlan planForBudget(const BudgetCostModel& model, double available_ms);

// "N tets T ms (decoding D), ..." and the floor: what the model was built from.
std::string describeBudgetModel(const BudgetCostModel& model);

}  // namespace gtn
