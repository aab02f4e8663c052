// <gatun/render.h>: rendering a .gtn file or mesh files to an image, PNG output.
// Part of the Gatun API; <gatun/gatun.h> includes every part and says how errors, ownership and
// threads work for all of them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "gatun/result.h"

namespace gatun {

/*-************************************
 *  Rendering
 **************************************/

/*! Image : 8-bit RGB pixels, row by row from the top left, 3 bytes per pixel, black background. */
struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;
};

/*! RenderOptions : the options of `gtn render` (its defaults).
 *  `width`, `height`: 1 to 4096 pixels. `perspective`: perspective instead of orthographic projection.
 *  `azimuth`, `elevation` (degrees), `zoom` (1 frames the bounding box): the camera.
 *  `field`: the point field shown: NAME, NAME:COMPONENT or NAME:mag; "" = the first point field that
 *     is not constant.
 *  `transfer`: a preset (cool-warm, grey, hot) or a transfer-function file (README.md).
 *  `range`: the scalar range of the transfer function; none = the boundary's values on level 0.
 *  `level` / `ratio`: render a stored level, or the mesh simplified to a ratio on the fly; neither =
 *     level 0. At most one.
 *  `face_sampling`: sample at tetrahedron faces instead of uniform steps. `step`: the volume sampling
 *     step (0 = diagonal / 400). `opacity_unit_distance`: as VTK's (0 = diagonal / 40).
 *  `use_cache`: read and write the render cache ($XDG_CACHE_HOME/gatun: level 0's colour ranges),
 *     which spares decoding level 0 to fix the range of a simplified view; the image is the same. */
struct RenderOptions {
  int width = 256, height = 256;
  bool perspective = false;
  double azimuth = 30, elevation = 20, zoom = 1;
  std::string field{};
  std::string transfer = "cool-warm";
  std::optional<std::pair<double, double>> range{};
  std::optional<size_t> level{};
  std::optional<double> ratio{};
  bool face_sampling = false;
  double step = 0;
  double opacity_unit_distance = 0;
  bool use_cache = false;
};

/*! render() : draws what `inputs` hold (one .gtn file, or mesh files as importMesh() takes them) with
 *  the streaming ray caster, as `gtn render` does with the same options: the same pixels.
 *  Errors: kUsage (bad options, a field the mesh lacks or a cell field, a level the file lacks),
 *  kInvalidData, kIo. */
Result<Image> render(const std::vector<std::string>& inputs, const RenderOptions& options = {});

/*! writePng() : writes `image` as an 8-bit RGB PNG file, atomically ("-" = standard output).
 *  Errors: kUsage (an image whose size does not match its pixels), kIo. */
Error writePng(const std::string& path, const Image& image);

}  // namespace gatun
