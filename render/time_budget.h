// Time-critical rendering (paper section 5): choose the stored level (and merges) that renders within
// a time budget, from a throughput model measured once per machine, file and render settings.
//
// Model: the time of a stored level (view fixing, decode and render) is piecewise linear in the
// logarithm of the tetrahedra decoded, between measured levels; the time of decoding it alone is
// piecewise linear in them. Simplifying on the fly still pays for decoding the whole level (the
// paper's section 6.1) but renders fewer tetrahedra: level i with m more merges is predicted as its
// decoding (plus 5% for the filter) and the rest of a run of the tetrahedra left, interpolated
// between level i's and level i+1's counts. The choice is the finest plan that fits 80% of the
// budget less what the run already spent (and less 1.5 times the learnt spread): a stored level as
// is, else level i with the fewest merges that fit, else the next level; below the coarsest
// level, its own tree's merges on the fly, down to the floor (the coarsest level merged down to
// LevelOptions::min_points vertices, or as it is when it has no more: coarser images no longer show
// the object), which is also what a budget nothing meets gets. Calibration times the coarsest level,
// the finest levels with at most a sixteenth and a quarter of level 0's tetrahedra, and level 0
// (after one warm-up run), whole and decoding alone, and the floor, and is cached in
// $XDG_CACHE_HOME/gatun/render-calibration.json (default ~/.cache/gatun/...) keyed by the file's path,
// size and modification time and the settings that change the cost (size, sampling, pipeline);
// standard input and pipes are calibrated every time, not cached, as is everything when
// RenderOptions::use_cache is false. A relative XDG_CACHE_HOME is ignored (the XDG specification). A
// cached calibration whose levels or floor are not the file's is made again.
#pragma once

#include <optional>
#include <string>
#include <utility>

#include "render/ray_cast.h"
#include "render/render_input.h"

namespace gtn {

// Chooses the level for `budget_ms` of which `elapsed_ms` are already spent; `explanation` receives a
// sentence saying what was measured or read from the cache, the model and the choice, and
// `predicted_ms` (optional) the predicted time of the rest of the run, and `shortfall` (optional) a
// sentence when even the floor is predicted to miss the budget, else nothing.
StatusOr<LevelChoice> chooseForBudget(RenderInput& input, const std::string& path, double budget_ms,
                                      const RenderOptions& options, bool generic, double elapsed_ms,
                                      std::string* explanation, double* predicted_ms = nullptr,
                                      std::string* shortfall = nullptr);

// After a budgeted run that used a cached calibration: moves the cached offset (added to every
// prediction) half way towards actual - predicted, and the cached spread (the room a plan keeps)
// towards |actual - predicted|, so that the model follows how fast runs are now.
void recordBudgetRun(const std::string& path, const RenderOptions& options, bool generic, double predicted_ms,
                     double actual_ms);

// Level 0's boundary range of `field` (the default colour range of every level's image), cached in
// the same file as the calibration for the file at `path` (keyed by its absolute path, size and
// modification time): a coarse level then need not decode level 0's boundary, which is a third of
// its run (blunt fin level 9 at 256x256: 26 -> 17 ms).
std::optional<std::pair<double, double>> cachedBoundaryRange(const std::string& path, const FieldSelector& field);
void storeBoundaryRange(const std::string& path, const FieldSelector& field, std::pair<double, double> range);

}  // namespace gtn
