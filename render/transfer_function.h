// Transfer function: a piecewise-linear map from a scalar to colour and opacity, over a scalar range.
//
// Opacity follows VTK's scalar-opacity convention: a control point's opacity `o` in [0, 1] is the
// opacity of a slab one "opacity unit distance" D thick, so the extinction coefficient is
// sigma = -ln(1 - o) / D and a ray step of length dt has alpha = 1 - exp(-sigma * dt). Images then do
// not depend on the sampling step or on the mesh density, and match VTK given the same D.
//
// Text file format (one directive per line, '#' starts a comment, blank lines ignored):
//   range LO HI          optional; the scalar range the positions refer to (default: auto)
//   point X R G B O      a control point: X in [0, 1] is the position within the range, R G B the
//                        colour in [0, 1], O the opacity per unit distance in [0, 1]
// At least two points, positions non-decreasing. Outside the range the end points apply.
#pragma once

#include <string>
#include <vector>

#include "mesh/status.h"

namespace gtn {

struct TransferPoint {
  double x = 0;        // position in [0, 1] of the scalar range
  double rgb[3] = {0, 0, 0};
  double opacity = 0;  // per opacity unit distance, in [0, 1]
};

struct TransferFunction {
  std::vector<TransferPoint> points;
  bool has_range = false;  // set by a file's `range` line or by the caller
  double lo = 0, hi = 1;

  // Colour and extinction (per unit length, before division by the unit distance: -ln(1 - o)).
  void evaluate(double scalar, double rgb[3], double* extinction) const;
};

// Names of the presets: "cool-warm" (the default: Moreland's diverging map, opacity ramping from 0 to
// 0.6 over the range), "grey" (black to white, linear ramp), "hot" (black-red-yellow-white, ramp).
const std::vector<std::string>& transferPresetNames();
StatusOr<TransferFunction> transferPreset(const std::string& name);
// Parses the text format above; `what` names the source in messages (file:line).
StatusOr<TransferFunction> parseTransferFunction(const std::string& text, const std::string& what);

}  // namespace gtn
