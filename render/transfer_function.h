// Transfer function: a piecewise-linear map from a scalar to colour and opacity, over a scalar range.
//
// Opacity follows VTK's unstructured-grid ray integrators (vtkUnstructuredGridVolumeRayCastMapper and
// its linear / pre-integration integrators): a control point's opacity `o` divided by the "opacity
// unit distance" D is the extinction (attenuation) coefficient sigma = o / D, linear in the scalar
// between control points, and a ray step of length dt has alpha = 1 - exp(-sigma * dt). Images then
// do not depend on the sampling step or on the mesh density, and match VTK's given the same points
// and the same D. (VTK's regular-grid mappers instead take o as the opacity of a slab D thick,
// sigma = -ln(1 - o) / D; the two agree for small o. We follow the unstructured-grid mapper, the one
// a tetrahedral renderer is compared with: bench/render/vtk_compare.py.)
//
// Text file format (one directive per line, '#' starts a comment, blank lines ignored):
//   range LO HI          optional; the scalar range the positions refer to (default: auto)
//   point X R G B O      a control point: X in [0, 1] is the position within the range, R G B the
//                        colour in [0, 1], O the opacity per unit distance in [0, 1] (see above)
// At least two points, positions non-decreasing. Outside the range the end points apply.
#pragma once

#include <string>
#include <vector>

#include "mesh/status.h"

namespace gtn {

struct TransferPoint {
  double x = 0;  // position in [0, 1] of the scalar range
  double rgb[3] = {0, 0, 0};
  double opacity = 0;  // per opacity unit distance, in [0, 1]
};

struct TransferFunction {
  std::vector<TransferPoint> points;
  bool has_range = false;  // set by a file's `range` line or by the caller
  double lo = 0, hi = 1;

  // Colour and extinction per unit distance (the interpolated opacity o; divide by D for sigma).
  void evaluate(double scalar, double rgb[3], double* extinction) const;
  // The position of a scalar in the range (0 at lo, 1 at hi, not clamped; 0.5 for an empty range),
  // and the scalar at a position: exact halves when hi - lo exceeds the largest double (a field with
  // -DBL_MAX and DBL_MAX sentinels), where the plain formulas overflow.
  double position(double scalar) const;
  double valueAt(double x) const;
};

// Names of the presets: "cool-warm" (the default: Moreland's diverging map, opacity ramping from 0 to
// 0.6 over the range), "grey" (black to white, linear ramp), "hot" (black-red-yellow-white, ramp).
const std::vector<std::string>& transferPresetNames();
StatusOr<TransferFunction> transferPreset(const std::string& name);
// Parses the text format above; `what` names the source in messages (file:line).
StatusOr<TransferFunction> parseTransferFunction(const std::string& text, const std::string& what);
// What `gtn render --transfer SPEC` and the API take: a file in the text format above when `spec` names a
// regular file (at most 1 MiB), else a preset's name. A name with a dot or a slash that is neither was
// meant as a file: an I/O error says whether it is missing or not a regular file.
StatusOr<TransferFunction> loadTransferFunction(const std::string& spec);

}  // namespace gtn
