// Time-critical rendering (paper section 5): choose the stored level (and merges) that renders within
// a time budget, from a throughput model measured once per machine, file and render settings.
//
// Model: end-to-end time = fixed + per_tet * (tetrahedra decoded). Decoding dominates and is paid for
// every tetrahedron of the level decoded, so simplifying further on the fly hardly saves time (the
// paper's section 6.1); the choice is therefore the finest stored level whose predicted time fits,
// with no extra merges. The model is calibrated by rendering the coarsest level and a level of about
// a sixteenth of the tetrahedra (or level 0 when the file has a single level), and cached in
// $XDG_CACHE_HOME/gatun/render-calibration.json (default ~/.cache/gatun/...) keyed by the file's path,
// size and modification time and the settings that change the cost (size, sampling, pipeline).
#pragma once

#include <string>

#include "render/ray_cast.h"
#include "render/render_input.h"

namespace gtn {

// Chooses the level for `budget_ms`; `explanation` receives a sentence saying what was measured or
// read from the cache, the model and the choice.
StatusOr<LevelChoice> chooseForBudget(RenderInput& input, const std::string& path, double budget_ms,
                                      const RenderOptions& options, bool generic, std::string* explanation);

}  // namespace gtn
