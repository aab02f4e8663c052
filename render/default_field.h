// The field `gtn render` shows when no --field is given: the first point field that is not constant
// (mesh/mesh_stats.h's defaultPointField), so that a file whose first field is constant (a PLOT3D Q
// file of uniform density) is not drawn as one flat colour.
#pragma once

#include <string>
#include <vector>

#include "render/render_input.h"

namespace gtn {

struct RenderFieldChoice {
  std::string name;                   // the field chosen; "" = the first (nothing to choose from)
  std::vector<std::string> constant;  // the point fields skipped as constant, in order
};

// Decides on the coarsest stored level (a field constant on level 0 is constant on every level, and
// one that varies on level 0 almost surely varies on the coarsest, which is the cheapest to decode;
// the decode stops as soon as the first field has varied). With fewer than two point fields there is
// nothing to choose and nothing is decoded.
StatusOr<RenderFieldChoice> chooseRenderField(RenderInput& input);

}  // namespace gtn
