// Rendering (include/gatun/render.h): the streaming renderer as `gtn render` runs it with the same
// options (no time budget, no generic pipeline).
#include <cmath>
#include <cstdio>
#include <utility>

#include "gatun/render.h"
#include "internal.h"
#include "render/default_field.h"
#include "render/image.h"
#include "render/render_input.h"
#include "render/stream_renderer.h"
#include "render/transfer_function.h"

namespace gatun {

namespace {
// The CLI's checks and defaults (cli/cmd_render.cpp, buildOptions), for the options of the API.
gtn::Status buildOptions(const RenderOptions& a, gtn::RenderOptions* o) {
  // The renderers keep about 100 bytes per pixel (rays, segments): bound the image.
  if (a.width <= 0 || a.height <= 0 || a.width > 4096 || a.height > 4096)
    return gtn::usageError("render: width and height must be 1 to 4096, not " + std::to_string(a.width) + "x" +
                           std::to_string(a.height));
  o->camera.width = a.width;
  o->camera.height = a.height;
  o->camera.projection = a.perspective ? gtn::Projection::kPerspective : gtn::Projection::kOrthographic;
  const std::pair<const char*, double> numbers[] = {{"azimuth", a.azimuth},
                                                    {"elevation", a.elevation},
                                                    {"zoom", a.zoom},
                                                    {"step", a.step},
                                                    {"opacity_unit_distance", a.opacity_unit_distance},
                                                    {"ratio", a.ratio.value_or(0)}};
  for (const auto& [name, value] : numbers)
    if (!std::isfinite(value)) return gtn::usageError(std::string("render: ") + name + " must be a finite number");
  if (a.range && !(std::isfinite(a.range->first) && std::isfinite(a.range->second) && a.range->first < a.range->second))
    return gtn::usageError("render: range must be two finite numbers LO < HI");
  if (!(a.zoom > 0)) return gtn::usageError("render: zoom must be positive");
  if (a.step < 0 || a.opacity_unit_distance < 0)
    return gtn::usageError("render: step and opacity_unit_distance must not be negative");
  if (a.level && a.ratio) return gtn::usageError("render: level and ratio exclude each other");
  o->camera.azimuth = a.azimuth;
  o->camera.elevation = a.elevation;
  o->camera.zoom = a.zoom;
  o->sampling = a.face_sampling ? gtn::Sampling::kFace : gtn::Sampling::kVolume;
  o->step = a.step;
  o->opacity_unit_distance = a.opacity_unit_distance;
  o->use_cache = a.use_cache;
  GTN_ASSIGN_OR_RETURN(o->field, gtn::parseFieldSelector(a.field));
  GTN_ASSIGN_OR_RETURN(o->transfer, gtn::loadTransferFunction(a.transfer));
  if (a.range) {
    o->transfer.has_range = true;
    o->transfer.lo = a.range->first;
    o->transfer.hi = a.range->second;
  }
  return gtn::Status::ok();
}

gtn::StatusOr<gtn::Image> renderImage(const std::vector<std::string>& inputs, const RenderOptions& a) {
  if (inputs.empty()) return gtn::usageError("render: no input file");
  gtn::RenderOptions options;
  GTN_RETURN_IF_ERROR(buildOptions(a, &options));
  GTN_ASSIGN_OR_RETURN(std::unique_ptr<gtn::RenderInput> input, gtn::RenderInput::open(inputs));
  if (a.field.empty()) {  // the default skips constant fields
    GTN_ASSIGN_OR_RETURN(gtn::RenderFieldChoice chosen, gtn::chooseRenderField(*input));
    options.field.name = chosen.name;
  }
  gtn::LevelChoice choice;
  if (a.level) choice.level = static_cast<int>(*a.level);
  if (a.ratio) choice.ratio = *a.ratio;
  GTN_ASSIGN_OR_RETURN(gtn::ResolvedLevel level, input->resolve(choice));
  // The field asked for, checked against the file before anything is decoded.
  GTN_RETURN_IF_ERROR(input->checkPointField(level, options.field, inputs[0]));
  GTN_RETURN_IF_ERROR(input->fixView(level, &options));
  // A step so small that the rays would take hours: at most 100000 samples across the box.
  if (options.step > 0 && options.has_scene_box) {
    double d2 = 0;
    for (int i = 0; i < 3; ++i)
      d2 += (options.scene_max[i] - options.scene_min[i]) * (options.scene_max[i] - options.scene_min[i]);
    if (std::sqrt(d2) / options.step > 100000) {
      char why[200];
      std::snprintf(why, sizeof why,
                    "render: step %g takes more than 100000 samples across the bounding box (diagonal %g)",
                    options.step, std::sqrt(d2));
      return gtn::usageError(why);
    }
  }
  gtn::StreamRenderer renderer(options);
  GTN_RETURN_IF_ERROR(input->stream(level, renderer, &options.field));
  return renderer.image();
}
}  // namespace

Result<Image> render(const std::vector<std::string>& inputs, const RenderOptions& options) {
  auto image = renderImage(inputs, options);
  if (!image.isOk()) return gtn::api::toError(image.status());
  Image out;
  out.width = image->width;
  out.height = image->height;
  out.rgb = std::move(image->rgb);
  return out;
}

Error writePng(const std::string& path, const Image& image) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgb.size() != static_cast<size_t>(image.width) * static_cast<size_t>(image.height) * 3)
    return Error(ErrorCode::kUsage, path + ": the image's pixels (" + std::to_string(image.rgb.size()) +
                                        " bytes) do not match its size " + std::to_string(image.width) + "x" +
                                        std::to_string(image.height));
  gtn::Image png(image.width, image.height);
  png.rgb = image.rgb;
  return gtn::api::toError(gtn::writePng(path, png));
}

}  // namespace gatun
