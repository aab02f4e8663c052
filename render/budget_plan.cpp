#include "render/budget_plan.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace gtn {

namespace {
// Whether `j` holds a number under `name`.
bool hasNumber(const nlohmann::json& j, const char* name) { return j.contains(name) && j[name].is_number(); }

// Appends the numbers of array `values` to `out`; false when one is not a number.
bool readNumbers(const nlohmann::json& values, std::vector<double>* out) {
  for (const nlohmann::json& v : values) {
    if (!v.is_number()) return false;
    out->push_back(v.get<double>());
  }
  return true;
}
}  // namespace

BudgetCalibration calibrationFromJson(const nlohmann::json* entry) {
  BudgetCalibration c;
  if (!entry || !entry->is_object() || !entry->contains("tets") || !entry->contains("ms")) return c;
  const nlohmann::json& tets = (*entry)["tets"];
  const nlohmann::json& ms = (*entry)["ms"];
  if (!tets.is_array() || !ms.is_array() || tets.size() != ms.size() || tets.empty()) return c;
  std::vector<double> t, m, d;
  if (!readNumbers(tets, &t) || !readNumbers(ms, &m)) return c;
  // An older entry, without decoding times: calibrate again.
  if (!entry->contains("decode_ms") || !(*entry)["decode_ms"].is_array() || (*entry)["decode_ms"].size() != t.size() ||
      !readNumbers((*entry)["decode_ms"], &d))
    return c;
  for (size_t i = 0; i < t.size(); ++i) {
    c.points.emplace_back(t[i], m[i]);
    c.decode_points.emplace_back(t[i], d[i]);
  }
  if (entry->contains("floor") && (*entry)["floor"].is_object()) {
    const nlohmann::json& f = (*entry)["floor"];
    if (hasNumber(f, "merges") && hasNumber(f, "tets") && hasNumber(f, "ms")) {
      c.floor_merges = f["merges"].get<double>();
      c.floor_tets = f["tets"].get<double>();
      c.floor_ms = f["ms"].get<double>();
    }
  }
  if (hasNumber(*entry, "offset_ms")) {
    const double v = (*entry)["offset_ms"].get<double>();
    if (std::fabs(v) <= kMaxBudgetOffsetMs) c.offset = v;
  }
  if (hasNumber(*entry, "spread_ms")) {
    const double v = (*entry)["spread_ms"].get<double>();
    if (v >= 0 && v <= kMaxBudgetOffsetMs) c.spread = v;
  }
  return c;
}

nlohmann::json calibrationToJson(const BudgetCalibration& c) {
  nlohmann::json tets = nlohmann::json::array(), ms = nlohmann::json::array(), dms = nlohmann::json::array();
  for (size_t i = 0; i < c.points.size(); ++i) {
    tets.push_back(c.points[i].first);
    ms.push_back(c.points[i].second);
    dms.push_back(c.decode_points[i].second);
  }
  nlohmann::json floor = nullptr;
  if (c.floor_merges > 0) floor = {{"merges", c.floor_merges}, {"tets", c.floor_tets}, {"ms", c.floor_ms}};
  return {{"tets", tets}, {"ms", ms}, {"decode_ms", dms}, {"offset_ms", c.offset}, {"floor", floor}};
}

bool calibrationNamesLevels(const BudgetCalibration& calibration, const std::vector<BudgetLevel>& levels) {
  return std::all_of(calibration.points.begin(), calibration.points.end(), [&](const auto& point) {
    return std::any_of(levels.begin(), levels.end(),
                       [&](const BudgetLevel& l) { return static_cast<double>(l.tets) == point.first; });
  });
}

std::vector<size_t> levelsToTime(const std::vector<BudgetLevel>& levels) {
  const size_t coarsest = levels.size() - 1;
  const uint64_t t0 = levels[0].tets;
  std::vector<size_t> timed = {coarsest, 0};
  for (uint64_t divisor : {16, 4}) {
    for (size_t i = 0; i < levels.size(); ++i) {
      if (levels[i].tets * divisor <= t0) {
        timed.push_back(i);
        if (divisor == 16)
          for (size_t j = i + 1; j < coarsest; ++j) timed.push_back(j);
        break;
      }
    }
  }
  std::sort(timed.begin(), timed.end());
  timed.erase(std::unique(timed.begin(), timed.end()), timed.end());
  return timed;
}

double interpolateCost(const std::vector<std::pair<double, double>>& points, double n, bool logarithmic) {
  if (points.empty()) return 0;
  if (points.size() == 1) return points[0].first > 0 ? points[0].second * n / points[0].first : points[0].second;
  size_t i = 1;
  while (i + 1 < points.size() && points[i].first < n) ++i;
  const auto& [n0, m0] = points[i - 1];
  const auto& [n1, m1] = points[i];
  auto x = [&](double v) { return logarithmic ? std::log(std::max(v, 1.0)) : v; };
  const double slope = x(n1) > x(n0) ? std::max(0.0, (m1 - m0) / (x(n1) - x(n0))) : 0.0;
  return std::max(0.0, m0 + slope * (x(n) - x(n0)));
}

BudgetCostModel::BudgetCostModel(BudgetCalibration calibration, std::vector<BudgetLevel> levels)
    : calibration_(std::move(calibration)), levels_(std::move(levels)) {
  std::sort(calibration_.points.begin(), calibration_.points.end());
  std::sort(calibration_.decode_points.begin(), calibration_.decode_points.end());
  const BudgetCalibration& c = calibration_;
  const double n_c = static_cast<double>(levels_.back().tets);
  has_floor_ = c.floor_merges >= 1 && c.floor_tets >= 0 && c.floor_tets < n_c && c.floor_ms > 0 &&
               c.floor_ms <= kMaxBudgetOffsetMs && levels_.back().has_tree;
}

// A whole run is interpolated in the logarithm of the tetrahedra: rendering has a large part that
// depends on the pixels and the samples, not on the mesh, so halving a coarse level saves a roughly
// constant time (blunt fin at 256x256: 25, 45, 72, 95 ms for 332, 468, 1189, 2499 tetrahedra), which
// a line through the calibrated levels misses by a factor of two. Decoding is linear in the
// tetrahedra.
double BudgetCostModel::whole(double n) const { return interpolateCost(calibration_.points, n, true); }

double BudgetCostModel::decoding(double n) const {
  return std::min(whole(n), interpolateCost(calibration_.decode_points, n, false));
}

bool BudgetCostModel::timed(uint64_t tets) const {
  return std::any_of(calibration_.points.begin(), calibration_.points.end(),
                     [&](const auto& p) { return p.first == static_cast<double>(tets); });
}

double BudgetCostModel::stored(size_t i) const {
  return std::max(0.0, calibration_.offset + whole(static_cast<double>(levels_[i].tets)));
}

// Level i with more merges: decoding level i is paid in full (plus the filter, a few percent); the
// rest is that of a run of the tetrahedra left, interpolated between level i's and the next stored
// level's counts by the merges.
double BudgetCostModel::merged(size_t i, double fraction) const {
  constexpr double kFilterCost = 1.05;
  const double n = static_cast<double>(levels_[i].tets);
  const double n_next = static_cast<double>(levels_[i + 1].tets);
  const double out = n + fraction * (n_next - n);
  return std::max(0.0, calibration_.offset + kFilterCost * decoding(n) + whole(out) - decoding(out));
}

// Beyond the coarsest level c: its tree's merges on the fly, the time interpolated (in the logarithm
// of the tetrahedra left) between the stored level's and the floor's.
double BudgetCostModel::floor(double fraction) const {
  const double n_c = static_cast<double>(levels_.back().tets);
  const std::vector<std::pair<double, double>> ends = {{calibration_.floor_tets, calibration_.floor_ms},
                                                       {n_c, whole(n_c)}};
  return std::max(0.0,
                  calibration_.offset + interpolateCost(ends, n_c + fraction * (calibration_.floor_tets - n_c), true));
}

std::optional<uint64_t> fewestMergesFitting(uint64_t span, double aim, const std::function<double(double)>& at) {
  if (span == 0 || at(1.0) > aim) return std::nullopt;
  double lo = 0, hi = 1;
  for (int it = 0; it < 40; ++it) {
    const double mid = 0.5 * (lo + hi);
    (at(mid) <= aim ? hi : lo) = mid;
  }
  const uint64_t e = static_cast<uint64_t>(std::ceil(hi * static_cast<double>(span)));
  return std::clamp<uint64_t>(e, 1, span);
}

BudgetPlan planForBudget(const BudgetCostModel& model, double available_ms) {
  // Plans aim at 80% of what remains: the same run on a 2-core machine scatters by +-15% from one
  // minute to the next (blunt fin level 8: 40-53 ms, then 57-82 ms), and the budget allows 10% more.
  constexpr double kMargin = 0.8;
  const double aim = std::min(kMargin * available_ms, available_ms - 1.5 * model.calibration().spread);
  const std::vector<BudgetLevel>& levels = model.levels();
  const size_t coarsest = levels.size() - 1;
  BudgetPlan plan;
  plan.choice.level = static_cast<int>(coarsest);
  plan.level = coarsest;
  plan.predicted = model.stored(coarsest);
  // Level i with e of `span` merges on the fly, predicted by at(e / span).
  auto takeMerged = [&](size_t i, uint64_t span, uint64_t e, const std::function<double(double)>& at) {
    plan.choice = LevelChoice();
    plan.choice.merges = static_cast<int64_t>(levels[i].merges + e);
    plan.level = i;
    plan.extra = e;
    plan.predicted = at(static_cast<double>(e) / static_cast<double>(span));
  };
  const std::function<double(double)> floor = [&](double fraction) { return model.floor(fraction); };
  const uint64_t floor_span = model.hasFloor() ? static_cast<uint64_t>(model.calibration().floor_merges) : 0;
  if (model.hasFloor()) takeMerged(coarsest, floor_span, floor_span, floor);  // until a plan fits: the cheapest
  for (size_t i = 0; i < levels.size(); ++i) {
    const double stored = model.stored(i);
    if (stored <= aim) {
      plan.choice = LevelChoice();
      plan.choice.level = static_cast<int>(i);
      plan.level = i;
      plan.extra = 0;
      plan.predicted = stored;
      break;
    }
    if (i + 1 >= levels.size()) {  // below the coarsest level: its own tree, down to the floor
      if (!model.hasFloor()) continue;
      if (auto e = fewestMergesFitting(floor_span, aim, floor)) {
        takeMerged(i, floor_span, *e, floor);
        break;
      }
      continue;
    }
    if (!levels[i].has_tree) continue;
    if (levels[i + 1].merges <= levels[i].merges) continue;  // not coarser: nothing between
    // Between two timed levels the next one is the plan: at the coarse end the time falls in steps
    // with the merges (blunt fin, level 8 plus 32 of the 41 merges to level 9: 24 ms; plus 40: 12
    // ms), so an interpolation would promise what the run then misses.
    if (model.timed(levels[i].tets) && model.timed(levels[i + 1].tets)) continue;
    const uint64_t span = levels[i + 1].merges - levels[i].merges;
    const std::function<double(double)> merged = [&](double fraction) { return model.merged(i, fraction); };
    if (auto e = fewestMergesFitting(span, aim, merged)) {
      takeMerged(i, span, *e, merged);
      break;
    }
  }
  return plan;
}

std::string describeBudgetModel(const BudgetCostModel& model) {
  const BudgetCalibration& c = model.calibration();
  std::string text;
  for (size_t i = 0; i < c.points.size(); ++i) {
    char p[96];
    std::snprintf(p, sizeof p, "%s%.0f tets %.1f ms (decoding %.1f)", text.empty() ? "" : ", ", c.points[i].first,
                  c.points[i].second, c.decode_points[i].second);
    text += p;
  }
  if (model.hasFloor()) {
    char p[128];
    std::snprintf(p, sizeof p, ", level %zu with %.0f merges of its tree %.0f tets %.1f ms", model.levels().size() - 1,
                  c.floor_merges, c.floor_tets, c.floor_ms);
    text += p;
  }
  return text;
}

}  // namespace gtn
