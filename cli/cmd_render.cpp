// gtn render INPUT -o IMAGE.png [options]: the streaming renderer (integrated decompression,
// simplification and ray casting), or the generic in-memory baseline.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "cli/progress_line.h"
#include "format/file_io.h"
#include "render/default_field.h"
#include "render/generic_renderer.h"
#include "render/render_input.h"
#include "render/stream_renderer.h"
#include "render/time_budget.h"

namespace gtn::cli {

namespace {
struct RenderArgs {
  std::vector<std::string> inputs;
  std::string output;
  std::string size = "256x256";
  std::string projection = "ortho";
  double azimuth = 30, elevation = 20, zoom = 1;
  std::string field;
  std::string transfer = "cool-warm";
  std::vector<double> range;
  double unit_distance = 0;
  std::string sampling = "volume";
  double step = 0;
  std::string pipeline = "integrated";
  int level = -1;
  double ratio = -1;
  int64_t merges = -1;
  double budget_ms = -1;
  std::string dump_view;
  bool verbose = false, json = false, no_cache = false;
};

// Whether two outputs, neither of which need exist yet, name one file ("x.png" and "./x.png").
bool samePathToBe(const std::string& a, const std::string& b) {
  namespace fs = std::filesystem;
  std::error_code ea, eb;
  const fs::path pa = fs::weakly_canonical(fs::absolute(a, ea), ea), pb = fs::weakly_canonical(fs::absolute(b, eb), eb);
  return !ea && !eb && pa == pb;
}

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

Status buildOptions(const RenderArgs& a, RenderOptions* o) {
  int w = 0, h = 0;
  char extra = 0;
  // The renderers keep about 100 bytes per pixel (rays, segments): bound the image.
  if (std::sscanf(a.size.c_str(), "%dx%d%c", &w, &h, &extra) != 2 || w <= 0 || h <= 0 || w > 4096 || h > 4096)
    return usageError("--size must be WxH with 1 <= W, H <= 4096, not '" + a.size + "'");
  o->camera.width = w;
  o->camera.height = h;
  if (a.projection == "ortho") o->camera.projection = Projection::kOrthographic;
  else if (a.projection == "persp") o->camera.projection = Projection::kPerspective;
  else return usageError("--projection must be ortho or persp");
  // Every number must be finite: a NaN or infinite camera angle left the rays undefined, and the
  // boundary's crossings were never sorted out (the render hung).
  const std::pair<const char*, double> numbers[] = {{"--azimuth", a.azimuth},
                                                    {"--elevation", a.elevation},
                                                    {"--zoom", a.zoom},
                                                    {"--step", a.step},
                                                    {"--opacity-unit-distance", a.unit_distance},
                                                    {"--ratio", a.ratio}};  // (--budget-ms: its validator)
  for (const auto& [name, value] : numbers)
    if (!std::isfinite(value)) return usageError(std::string(name) + " must be a finite number");
  for (double v : a.range)
    if (!std::isfinite(v)) return usageError("--range must be two finite numbers");
  o->camera.azimuth = a.azimuth;
  o->camera.elevation = a.elevation;
  if (!(a.zoom > 0)) return usageError("--zoom must be positive");
  o->camera.zoom = a.zoom;
  if (a.sampling == "volume") o->sampling = Sampling::kVolume;
  else if (a.sampling == "face") o->sampling = Sampling::kFace;
  else return usageError("--sampling must be volume or face");
  if (a.step < 0 || a.unit_distance < 0) return usageError("--step and --opacity-unit-distance must be positive");
  o->step = a.step;
  o->opacity_unit_distance = a.unit_distance;
  o->use_cache = !a.no_cache;
  GTN_ASSIGN_OR_RETURN(o->field, parseFieldSelector(a.field));
  GTN_ASSIGN_OR_RETURN(o->transfer, loadTransferFunction(a.transfer));
  if (!a.range.empty()) {
    if (a.range.size() != 2 || !(a.range[0] < a.range[1])) return usageError("--range needs LO HI with LO < HI");
    o->transfer.has_range = true;
    o->transfer.lo = a.range[0];
    o->transfer.hi = a.range[1];
  }
  return Status::ok();
}

// The camera and transfer function a render used, in vtkCamera / vtkVolumeProperty terms, so that
// another renderer (bench/render/vtk_compare.py) reproduces the view instead of re-deriving defaults.
nlohmann::json describeSetup(const RenderSetup& s) {
  const Camera& c = s.camera;
  auto vec = [](const double* v) { return nlohmann::json::array({v[0], v[1], v[2]}); };
  nlohmann::json cam = {{"width", c.width()},
                        {"height", c.height()},
                        {"projection", c.options().projection == Projection::kOrthographic ? "ortho" : "persp"},
                        {"position", vec(c.position())},
                        {"focal_point", vec(c.focalPoint())},
                        {"view_up", vec(c.viewUp())},
                        {"parallel_scale", c.parallelScale()},
                        {"view_angle", c.viewAngleDeg()},
                        {"pixel_centres", true}};
  nlohmann::json points = nlohmann::json::array();
  const TransferFunction& tf = s.transfer;
  for (const TransferPoint& p : tf.points) {
    points.push_back(
        {{"x", p.x}, {"value", tf.valueAt(p.x)}, {"rgb", {p.rgb[0], p.rgb[1], p.rgb[2]}}, {"opacity", p.opacity}});
  }
  return {{"camera", cam},
          {"transfer",
           {{"field", s.field},
            {"range", {tf.lo, tf.hi}},
            {"points", points},
            {"opacity_unit_distance", 1.0 / s.inv_unit_distance}}},
          {"sampling", s.sampling == Sampling::kFace ? "face" : "volume"},
          {"step", s.step},
          {"background", {0, 0, 0}}};
}

// One render of the resolved level; fills `report` with what happened (and `report["view"]` with the
// resolved camera and transfer function).
StatusOr<Image> renderOnce(RenderInput& input, ResolvedLevel& level, const RenderOptions& options, bool generic,
                           nlohmann::json& report) {
  if (generic) {
    TetMeshBuilder builder;
    const Clock::time_point t0 = Clock::now();
    GTN_RETURN_IF_ERROR(input.stream(level, builder, &options.field));
    report["decode_ms"] = msSince(t0);
    GenericRenderStats stats;
    const Clock::time_point t1 = Clock::now();
    GTN_ASSIGN_OR_RETURN(Image image,
                         renderGeneric(builder.header(), builder.mesh(), builder.boundary(), options, &stats));
    report["render_ms"] = msSince(t1);
    report["tets_rendered"] = stats.tets;
    report["segments"] = stats.segments;
    report["lost_cursors"] = stats.lost_cursors;
    report["lost_rays"] = stats.lost_rays;
    report["view"] = describeSetup(stats.setup);
    return image;
  }
  StreamRenderer renderer(options);
  GTN_RETURN_IF_ERROR(input.stream(level, renderer, &options.field));
  const StreamRenderStats& s = renderer.stats();
  report["tets_rendered"] = s.tets;
  report["tets_held"] = s.tets_held;
  report["peak_tets_held"] = s.peak_tets_held;
  report["peak_vertices"] = s.peak_vertices;
  report["peak_face_entries"] = s.peak_face_entries;
  report["segments"] = s.segments;
  report["lost_cursors"] = s.lost_cursors;
  report["lost_rays"] = s.lost_rays;
  report["tets_left_held"] = s.tets_left_held;
  report["view"] = describeSetup(renderer.setup());
  return renderer.image();
}

int runRender(const RenderArgs& a) {
  const Clock::time_point start = Clock::now();
  RenderOptions options;
  if (Status st = buildOptions(a, &options); !st.isOk()) return reportError(st);
  const int chosen = (a.level >= 0) + (a.ratio >= 0) + (a.merges >= 0) + (a.budget_ms >= 0);
  if (chosen > 1) return reportError(usageError("use at most one of --level, --ratio, --merges and --budget-ms"));
  for (const std::string& in : a.inputs)
    for (const std::string& out : {a.output, a.dump_view})
      if (!out.empty() && (in == out || sameFile(in, out)))
        return reportError(usageError(out + ": the output would overwrite an input"));
  // The image and the view in one file (the view replaced the image), or two documents on standard
  // output together (the PNG's bytes and the JSON interleaved).
  const int to_stdout = (a.output == "-") + (a.dump_view == "-") + a.json;
  if (to_stdout > 1)
    return reportError(usageError("only one of -o -, --dump-view - and --json can write to standard output"));
  if (!a.dump_view.empty() &&
      (a.dump_view == a.output || sameFile(a.dump_view, a.output) || samePathToBe(a.dump_view, a.output)))
    return reportError(usageError(a.output + ": -o and --dump-view name the same file"));
  auto input = RenderInput::open(a.inputs);
  if (!input.isOk()) return reportError(input.status());
  HeldWarnings damage;  // said once the outcome is known: the error alone names a chunk the render needed
  for (const std::string& w : (*input)->warnings()) damage.sink()(w);
  auto fail = [&](const Status& st) {
    damage.flush(st);
    return reportError(st);
  };
  if (a.field.empty()) {  // the default skips constant fields, and says so
    auto chosen = chooseRenderField(**input);
    if (!chosen.isOk()) return fail(chosen.status());
    options.field.name = chosen->name;
    if (!chosen->constant.empty()) {
      std::string names;
      for (const std::string& n : chosen->constant) names += (names.empty() ? "'" : ", '") + n + "'";
      const std::string shown = chosen->name.empty() ? "the first field, though every point field is constant"
                                                     : "field '" + chosen->name + "'";
      std::fprintf(stderr, "gtn: render: showing %s (constant: %s; --field chooses another)\n", shown.c_str(),
                   names.c_str());
    }
  }
  const bool generic = a.pipeline == "generic";
  nlohmann::json report;
  LevelChoice choice;
  double predicted_ms = 0, budget_start_ms = 0;
  bool calibrated_now = false;
  choice.level = a.level;
  choice.ratio = a.ratio;
  choice.merges = a.merges;
  if (a.budget_ms >= 0) {
    std::string explanation, shortfall;
    budget_start_ms = msSince(start);
    auto budget = chooseForBudget(**input, a.inputs[0], a.budget_ms, options, generic, budget_start_ms, &explanation,
                                  &predicted_ms, &shortfall);
    if (!budget.isOk()) return fail(budget.status());
    choice = budget.value();
    report["budget_ms"] = a.budget_ms;
    report["budget_choice"] = explanation;
    report["budget_met"] = shortfall.empty();  // as predicted
    calibrated_now = explanation.rfind("calibrated", 0) == 0;
    budget_start_ms = msSince(start);  // the rest of the run is what was predicted
    if (a.verbose) std::fprintf(stderr, "gtn: render: %s\n", explanation.c_str());
    if (!shortfall.empty()) warn(a.inputs[0] + ": " + shortfall);
  }
  auto level = (*input)->resolve(choice);
  if (!level.isOk()) return fail(level.status());
  // The field asked for, checked against the file before anything is decoded.
  if (Status st = (*input)->checkPointField(*level, options.field, a.inputs[0]); !st.isOk()) return fail(st);
  if (Status st = (*input)->fixView(level.value(), &options); !st.isOk()) return fail(st);
  // A step so small that the rays would take hours (1e-9 ran for minutes): at most kMaxSteps samples
  // across the box (the default takes 400).
  constexpr double kMaxSteps = 100000;
  if (options.step > 0 && options.has_scene_box) {
    double d2 = 0;
    for (int i = 0; i < 3; ++i)
      d2 += (options.scene_max[i] - options.scene_min[i]) * (options.scene_max[i] - options.scene_min[i]);
    if (std::sqrt(d2) / options.step > kMaxSteps) {
      char why[200];
      std::snprintf(why, sizeof why,
                    "--step %g takes more than 100000 samples across the bounding box (diagonal %g); the default "
                    "is the diagonal / 400",
                    options.step, std::sqrt(d2));
      return fail(usageError(why));
    }
    // The other end: samples so far apart that most rays take none (spx with --step 20: a blank image).
    if (options.sampling == Sampling::kVolume && std::sqrt(d2) < 4 * options.step) {
      char why[200];
      std::snprintf(why, sizeof why,
                    "--step %g takes fewer than 4 samples across the bounding box (diagonal %g): most rays take "
                    "none, and the image may be blank",
                    options.step, std::sqrt(d2));
      warn(a.inputs[0] + ": " + why);
    }
  }
  ProgressLine progress("gtn render", true);  // on a terminal: the share of the level decoded and rendered
  (*input)->setProgress(progress.callback());
  auto image = renderOnce(**input, level.value(), options, generic, report);
  progress.clear();
  if (!image.isOk()) return fail(image.status());
  damage.flush();
  if (Status st = writePng(a.output, image.value()); !st.isOk()) return fail(st);
  if (!a.dump_view.empty()) {
    const std::string text = jsonText(report["view"]) + "\n";
    if (Status st = writeBytesAtomically(a.dump_view, text.data(), text.size()); !st.isOk()) return fail(st);
  }
  const double total_ms = msSince(start);
  if (a.budget_ms >= 0 && !calibrated_now)
    recordBudgetRun(a.inputs[0], options, generic, predicted_ms, total_ms - budget_start_ms);
  report["input"] = a.inputs;
  report["output"] = a.output;
  report["pipeline"] = generic ? "generic" : "integrated";
  report["level"] = level->level;
  report["stored_merges"] = level->stored_merges;
  report["extra_merges"] = level->extra_merges;
  // As --ratio and the stored levels count it: over the points that tetrahedra use.
  // Level 0's merge tree says how many; without merges, or where that tree cannot be read (the
  // render did not need it), every point counts.
  uint64_t unused = 0;
  if (level->total_merges() > 0)
    if (auto u = (*input)->unreferencedMerges(); u.isOk()) unused = *u;
  const uint64_t used_points = (*input)->levelZeroPoints() - std::min(unused, (*input)->levelZeroPoints());
  const uint64_t ratio_merges = level->total_merges() - std::min(unused, level->total_merges());
  report["ratio"] = used_points ? static_cast<double>(ratio_merges) / static_cast<double>(used_points) : 0.0;
  report["tets_decoded"] = level->tets;
  report["total_ms"] = total_ms;
  if (a.json) {
    std::printf("%s\n", jsonText(report).c_str());
  } else if (a.verbose || a.budget_ms >= 0) {
    std::fprintf(stderr, "gtn: render: level %zu + %llu merges (ratio %.4f), %llu tetrahedra decoded, %.1f ms\n",
                 level->level, static_cast<unsigned long long>(level->extra_merges), report["ratio"].get<double>(),
                 static_cast<unsigned long long>(level->tets), total_ms);
  }
  return 0;
}
}  // namespace

Command addRenderCommand(CLI::App& app) {
  auto a = std::make_shared<RenderArgs>();
  CLI::App* sub = app.add_subcommand("render", "Render a volume mesh to a PNG image (streaming ray casting)");
  sub->add_option("inputs", a->inputs, "a .gtn file, or the input(s) of any mesh the importers read")->required();
  sub->add_option("-o,--output", a->output, "output PNG image")->required();
  sub->add_option("--size", a->size, "image size WxH (default 256x256)");
  sub->add_option("--projection", a->projection, "ortho (default) or persp");
  sub->add_option("--azimuth", a->azimuth, "camera azimuth in degrees about +y (default 30)");
  sub->add_option("--elevation", a->elevation, "camera elevation in degrees (default 20)");
  sub->add_option("--zoom", a->zoom, "magnification; 1 frames the bounding box (default 1)");
  sub->add_option("--field", a->field,
                  "point field to render: NAME, NAME:COMPONENT or NAME:mag (default: the first that is not constant)");
  sub->add_option("--transfer", a->transfer,
                  "transfer function: a preset (cool-warm, grey, hot) or a file of 'range LO HI' and 'point X R G B O' "
                  "lines (README)");
  sub->add_option("--range", a->range, "scalar range LO HI of the transfer function (default: the boundary's)")
      ->expected(2);
  sub->add_option("--opacity-unit-distance", a->unit_distance,
                  "distance over which a transfer-function opacity applies, as VTK (default: diagonal / 40)");
  sub->add_option("--sampling", a->sampling, "volume (uniform steps, default) or face (at tetrahedron faces)");
  sub->add_option("--step", a->step, "volume sampling step (default: diagonal / 400)");
  sub->add_option("--pipeline", a->pipeline, "integrated (streaming, default) or generic (whole mesh in memory)")
      ->check(CLI::IsMember({"integrated", "generic"}));
  // Checked here: a negative value meant "not given" below, and was ignored silently.
  sub->add_option("--level", a->level, "render stored level I as is")->check(finiteAtLeastZero());
  sub->add_option("--ratio", a->ratio,
                  "simplification ratio in [0, 1]: vertices merged away / vertices of level 0 that tetrahedra use")
      ->check(CLI::Range(0.0, 1.0));
  sub->add_option("--merges", a->merges, "number of merges of the merge tree to apply")->check(finiteAtLeastZero());
  sub->add_option("--budget-ms", a->budget_ms, "choose level and merges to render within T milliseconds")
      ->check(finiteAtLeastZero(true));
  sub->add_option("--dump-view", a->dump_view,
                  "write the camera and transfer function used (vtkCamera / vtkVolumeProperty terms) as JSON");
  sub->add_flag("--no-cache", a->no_cache,
                "neither read nor write the render cache ($XDG_CACHE_HOME/gatun: budget calibrations, colour ranges)");
  sub->add_flag("-v,--verbose", a->verbose, "say what was chosen and how long it took");
  sub->add_flag("--json", a->json, "write a JSON report to standard output");
  return {sub, [a] { return runRender(*a); }};
}

}  // namespace gtn::cli
