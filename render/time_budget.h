// Time-critical rendering (paper section 5): choose the stored level (and merges) that renders within
// a time budget, from a throughput model measured once per machine, file and render settings.
//
// Model: the time of a level (view fixing, decode and render) is piecewise linear in the tetrahedra
// decoded, between measured levels. Decoding is paid for every tetrahedron of the level decoded, so
// simplifying further on the fly hardly saves time (the paper's section 6.1); the choice is therefore
// the finest stored level whose predicted time fits in the budget less what the run already spent,
// with no extra merges. Calibration times the coarsest level, the finest levels with at most a
// sixteenth and a quarter of level 0's tetrahedra, and level 0 (after one warm-up run), and is cached in
// $XDG_CACHE_HOME/gatun/render-calibration.json (default ~/.cache/gatun/...) keyed by the file's path,
// size and modification time and the settings that change the cost (size, sampling, pipeline).
#pragma once

#include <string>

#include "render/ray_cast.h"
#include "render/render_input.h"

namespace gtn {

// Chooses the level for `budget_ms` of which `elapsed_ms` are already spent; `explanation` receives a
// sentence saying what was measured or read from the cache, the model and the choice, and
// `predicted_ms` (optional) the predicted time of the rest of the run.
StatusOr<LevelChoice> chooseForBudget(RenderInput& input, const std::string& path, double budget_ms,
                                      const RenderOptions& options, bool generic, double elapsed_ms,
                                      std::string* explanation, double* predicted_ms = nullptr);

// After a budgeted run that used a cached calibration: moves the cached speed factor (which scales
// every prediction) half way, geometrically, towards actual / predicted, so that the model follows
// how fast the machine is now (a shared machine's speed varies with its load).
void recordBudgetRun(const std::string& path, const RenderOptions& options, bool generic, double predicted_ms,
                     double actual_ms);

}  // namespace gtn
