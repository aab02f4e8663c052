#include "render/time_budget.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "format/file_io.h"
#include "render/budget_plan.h"
#include "render/generic_renderer.h"
#include "render/stream_renderer.h"
#include "simplify/levels.h"

namespace gtn {

namespace {
// $XDG_CACHE_HOME/gatun/render-calibration.json, or under $HOME/.cache when XDG_CACHE_HOME is unset,
// empty or relative (the XDG base directory specification: a relative path is invalid, ignored).
std::string cachePath() {
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  std::string base;
  if (xdg && *xdg == '/') base = xdg;
  else if (const char* home = std::getenv("HOME"); home && *home) base = std::string(home) + "/.cache";
  else {
    std::error_code ec;  // TMPDIR naming no folder: /tmp, rather than an exception that aborts the program
    const std::filesystem::path temp = std::filesystem::temp_directory_path(ec);
    base = ec ? std::string("/tmp") : temp.string();
  }
  return base + "/gatun/render-calibration.json";
}

// The file's identity: absolute path, size and modification time.
std::string fileKey(const std::string& path) {
  struct stat st {};
  std::string abs = path;
  std::error_code ec;
  const auto p = std::filesystem::absolute(path, ec);
  if (!ec) abs = p.string();
  if (::stat(path.c_str(), &st) != 0) st = {};
  return abs + "|" + std::to_string(st.st_size) + "|" + std::to_string(st.st_mtime);
}

// Whether what is cached for `path` can be found again: a regular file, known by its path, size and
// modification time. Standard input ("-") and pipes are other streams every time (they all had the
// key of "-": one stream's calibration and colour range served the next).
bool cacheable(const std::string& path) {
  struct stat st {};
  return path != "-" && ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

// The merges of the coarsest level's tree that the cheapest plan applies on the fly: down to
// LevelOptions::min_points vertices (the fewest the automatic levels keep), never further. Merging
// on to the last tetrahedron met any budget with an image that no longer showed the object (one
// tetrahedron); a coarsest level with no more vertices than that is the floor as it is.
StatusOr<uint64_t> floorMerges(RenderInput& input) {
  const size_t coarsest = input.levels() - 1;
  GTN_ASSIGN_OR_RETURN(const uint64_t tree, input.mergeTreeMerges(coarsest));
  const uint64_t points = input.levelHeader(coarsest).points, keep = LevelOptions().min_points;
  return points > keep ? std::min(tree, points - keep) : 0;
}

// The field is part of the key: a run decodes the values of the rendered field alone.
std::string cacheKey(const std::string& path, const RenderOptions& o, bool generic) {
  return fileKey(path) + "|" + std::to_string(o.camera.width) + "x" + std::to_string(o.camera.height) + "|" +
         (o.sampling == Sampling::kFace ? "face" : "volume") + "|" + (generic ? "generic" : "integrated") + "|field " +
         o.field.name + "|" + o.field.whole;
}

// Time of one end-to-end render of `choice` (decode + render; the image is kept in `image` when
// given, and the tetrahedra rendered, after the merges on the fly, in `tets_out`).
StatusOr<double> timeChoice(RenderInput& input, const LevelChoice& choice, const RenderOptions& options, bool generic,
                            Image* image_out = nullptr, uint64_t* tets_out = nullptr) {
  GTN_ASSIGN_OR_RETURN(ResolvedLevel resolved, input.resolve(choice));
  const auto t0 = std::chrono::steady_clock::now();
  RenderOptions fixed = options;  // as the real run will: its view fixing is part of the time
  GTN_RETURN_IF_ERROR(input.fixView(resolved, &fixed));
  if (generic) {
    TetMeshBuilder builder;
    GTN_RETURN_IF_ERROR(input.stream(resolved, builder, &fixed.field));
    GTN_ASSIGN_OR_RETURN(Image image, renderGeneric(builder.header(), builder.mesh(), builder.boundary(), fixed));
    if (image_out) *image_out = std::move(image);
    if (tets_out) *tets_out = builder.mesh().numTets();
  } else {
    StreamRenderer renderer(fixed);
    GTN_RETURN_IF_ERROR(input.stream(resolved, renderer, &fixed.field));
    if (image_out) *image_out = renderer.image();
    if (tets_out) *tets_out = renderer.stats().tets;
  }
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}
StatusOr<double> timeLevel(RenderInput& input, size_t level, const RenderOptions& options, bool generic,
                           Image* image_out = nullptr) {
  LevelChoice choice;
  choice.level = static_cast<int>(level);
  return timeChoice(input, choice, options, generic, image_out);
}
// Time of decoding stored level `level` alone (the field a render reads), into a sink that keeps
// nothing: the part of a run that simplifying on the fly cannot save.
StatusOr<double> timeDecode(RenderInput& input, size_t level, const FieldSelector& field) {
  LevelChoice choice;
  choice.level = static_cast<int>(level);
  GTN_ASSIGN_OR_RETURN(ResolvedLevel resolved, input.resolve(choice));
  const auto t0 = std::chrono::steady_clock::now();
  CountingSink sink;
  GTN_RETURN_IF_ERROR(input.stream(resolved, sink, &field));
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// The cache: every calibration and colour range, one JSON object (an empty one when the file is
// missing or does not parse). A cache that cannot be written only costs a calibration next time.
nlohmann::json readCache(const std::string& cache_file) {
  nlohmann::json cache = nlohmann::json::object();
  if (auto text = readWholeFile(cache_file, 1 << 24); text.isOk()) {
    cache = nlohmann::json::parse(text.value(), nullptr, false);
    if (!cache.is_object()) cache = nlohmann::json::object();
  }
  return cache;
}
void writeCache(const std::string& cache_file, const nlohmann::json& cache) {
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(cache_file).parent_path(), ec);
  const std::string text = cache.dump(1, ' ', false, nlohmann::json::error_handler_t::replace);
  (void)writeBytesAtomically(cache_file, text.data(), text.size(), /*sync=*/false);
}

std::vector<BudgetLevel> budgetLevels(const RenderInput& input) {
  std::vector<BudgetLevel> levels(input.levels());
  for (size_t i = 0; i < levels.size(); ++i)
    levels[i] = {input.levelHeader(i).tets, input.levelHeader(i).merges, input.hasMergeTree(i)};
  return levels;
}

// A calibration names the file's levels and its coarsest tree: another file under the same key
// (replaced within the same second by one of the same size) is calibrated again, not planned with
// them (a floor of more merges than the tree holds failed the run).
bool calibrationFitsFile(const BudgetCalibration& calibration, const std::vector<BudgetLevel>& levels,
                         RenderInput& input) {
  bool same = calibrationNamesLevels(calibration, levels);
  if (calibration.floor_merges > 0) {
    auto merges = floorMerges(input);
    same &= merges.isOk() && static_cast<double>(*merges) == calibration.floor_merges;
  }
  return same;
}

// What a real run costs beyond the calibration's timings, first estimate: a run is a fresh process
// (cold memory, a new thread pool) that also writes the image, which the calibration, timed in one
// warm process, does not see. At the coarse end this is most of the error, and it adds rather than
// scales (blunt fin at 256x256: about 20 ms on runs of 30-60 ms). The warm-up run of the coarsest
// level (which warms the file and the thread pool) is timed: what it takes beyond the warm run of
// the same level, plus writing the image (to `probe`, then removed).
StatusOr<double> measureRunOverhead(RenderInput& input, const RenderOptions& options, bool generic,
                                    const std::string& probe) {
  const size_t coarsest = input.levels() - 1;
  GTN_ASSIGN_OR_RETURN(const double cold_ms, timeLevel(input, coarsest, options, generic));
  Image image;
  GTN_ASSIGN_OR_RETURN(const double warm_ms, timeLevel(input, coarsest, options, generic, &image));
  const auto t0 = std::chrono::steady_clock::now();
  const Status written = writePng(probe, image);
  const double png_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::error_code ec;
  std::filesystem::remove(probe, ec);
  return std::max(0.0, cold_ms - warm_ms) + (written.isOk() ? png_ms : 0.0);
}

// Times the levels levelsToTime names, whole and decoding alone, after the warm-up run
// (measureRunOverhead, writing its image to `probe`), and the floor. `names` receives the levels
// timed, as the explanation says them.
StatusOr<BudgetCalibration> calibrate(RenderInput& input, const RenderOptions& options, bool generic,
                                      const std::string& probe, std::string* names) {
  const std::vector<BudgetLevel> levels = budgetLevels(input);
  const size_t coarsest = levels.size() - 1;
  const std::vector<size_t> timed = levelsToTime(levels);
  BudgetCalibration c;
  GTN_ASSIGN_OR_RETURN(c.offset, measureRunOverhead(input, options, generic, probe));
  names->clear();
  for (size_t level : timed) {
    GTN_ASSIGN_OR_RETURN(double t, timeLevel(input, level, options, generic));
    GTN_ASSIGN_OR_RETURN(double d, timeDecode(input, level, options.field));
    const double n = static_cast<double>(levels[level].tets);
    c.points.emplace_back(n, t);
    c.decode_points.emplace_back(n, std::min(d, t));
    *names += (names->empty() ? "" : ", ") + std::to_string(level);
  }
  GTN_ASSIGN_OR_RETURN(const uint64_t tree_merges, floorMerges(input));
  if (tree_merges > 0) {
    LevelChoice all;
    all.merges = static_cast<int64_t>(levels[coarsest].merges + tree_merges);
    uint64_t rendered = 0;
    GTN_ASSIGN_OR_RETURN(c.floor_ms, timeChoice(input, all, options, generic, nullptr, &rendered));
    c.floor_merges = static_cast<double>(tree_merges);
    c.floor_tets = static_cast<double>(rendered);
    *names += " and " + std::to_string(coarsest) + " with " + std::to_string(tree_merges) + " merges of its tree";
  }
  return c;
}

// Where the warm-up image is written: beside the cache, or (nothing cached) in the temporary directory.
std::string probePath(const std::string& cache_file, bool cached) {
  std::error_code ec;
  if (cached) {
    std::filesystem::create_directories(std::filesystem::path(cache_file).parent_path(), ec);
    return cache_file + ".probe.png";
  }
  return (std::filesystem::temp_directory_path(ec) / ("gatun-render-probe-" + std::to_string(::getpid()) + ".png"))
      .string();
}

// The explanation's sentence: where the calibration came from, the model, and the plan.
std::string explainPlan(const std::string& source, const BudgetCostModel& model, const BudgetPlan& plan,
                        double elapsed_ms, double budget_ms) {
  const BudgetLevel& level = model.levels()[plan.level];
  char buf[1024];
  std::snprintf(buf, sizeof buf,
                "%s; measured %s, learnt offset %+.1f ms, spread %.1f ms; level %zu (%llu tetrahedra, %llu merges) + "
                "%llu merges on the fly "
                "predicted %.1f ms + %.1f ms already spent for a budget of %.1f ms%s",
                source.c_str(), describeBudgetModel(model).c_str(), model.calibration().offset,
                model.calibration().spread, plan.level, static_cast<unsigned long long>(level.tets),
                static_cast<unsigned long long>(level.merges), static_cast<unsigned long long>(plan.extra),
                plan.predicted, elapsed_ms, budget_ms,
                plan.predicted > budget_ms - elapsed_ms ? " (the cheapest plan; the budget cannot be met)" : "");
  return buf;
}

// The sentence for a plan predicted to miss the budget.
std::string shortfallOf(const BudgetPlan& plan, double elapsed_ms, double budget_ms) {
  char buf[1024];
  std::snprintf(buf, sizeof buf,
                "--budget-ms %g cannot be met: the cheapest plan that still shows the mesh, level %zu + %llu merges "
                "on the fly, is predicted at %.1f ms (%.1f ms already spent); rendering it",
                budget_ms, plan.level, static_cast<unsigned long long>(plan.extra), plan.predicted, elapsed_ms);
  return buf;
}
}  // namespace

StatusOr<LevelChoice> chooseForBudget(RenderInput& input, const std::string& path, double budget_ms,
                                      const RenderOptions& options, bool generic, double elapsed_ms,
                                      std::string* explanation, double* predicted_ms, std::string* shortfall) {
  if (!(budget_ms > 0)) return usageError("--budget-ms must be positive");
  const std::string key = "v4|" + cacheKey(path, options, generic);
  const std::string cache_file = cachePath();
  const bool cached = options.use_cache && cacheable(path);
  nlohmann::json cache = cached ? readCache(cache_file) : nlohmann::json::object();
  const std::vector<BudgetLevel> levels = budgetLevels(input);
  BudgetCalibration calibration = calibrationFromJson(cache.contains(key) ? &cache[key] : nullptr);
  std::string source = "calibration read from " + cache_file;
  if (!calibration.points.empty() && !calibrationFitsFile(calibration, levels, input)) calibration = {};
  if (calibration.points.empty()) {
    std::string names;
    GTN_ASSIGN_OR_RETURN(calibration, calibrate(input, options, generic, probePath(cache_file, cached), &names));
    if (cached) {
      cache[key] = calibrationToJson(calibration);
      writeCache(cache_file, cache);
      source = "calibrated on levels " + names + ", cached in " + cache_file;
    } else if (!options.use_cache) {
      source = "calibrated on levels " + names + ", not cached (--no-cache)";
    } else {
      source = "calibrated on levels " + names + ", not cached (" + (path == "-" ? "standard input" : path) +
               " is no regular file)";
    }
  }
  const BudgetCostModel model(std::move(calibration), levels);
  // What the run has spent before rendering (opening the input, this choice) counts against the
  // budget too.
  const double available = budget_ms - elapsed_ms;
  const BudgetPlan plan = planForBudget(model, available);
  *explanation = explainPlan(source, model, plan, elapsed_ms, budget_ms);
  if (predicted_ms) *predicted_ms = plan.predicted;
  if (shortfall) *shortfall = plan.predicted > available ? shortfallOf(plan, elapsed_ms, budget_ms) : std::string();
  return plan.choice;
}

void recordBudgetRun(const std::string& path, const RenderOptions& options, bool generic, double predicted_ms,
                     double actual_ms) {
  if (!(predicted_ms > 0) || !(actual_ms > 0) || !options.use_cache || !cacheable(path)) return;
  const std::string key = "v4|" + cacheKey(path, options, generic);
  const std::string cache_file = cachePath();
  nlohmann::json cache = readCache(cache_file);
  if (!cache.contains(key) || !cache[key].is_object()) return;
  nlohmann::json& entry = cache[key];
  double offset =
      entry.contains("offset_ms") && entry["offset_ms"].is_number() ? entry["offset_ms"].get<double>() : 0.0;
  if (!(std::fabs(offset) <= kMaxBudgetOffsetMs)) offset = 0;
  double spread =
      entry.contains("spread_ms") && entry["spread_ms"].is_number() ? entry["spread_ms"].get<double>() : 0.0;
  if (!(spread >= 0 && spread <= kMaxBudgetOffsetMs)) spread = 0;
  // Half way towards what this run says, so that one outlier does not swing it; the spread follows
  // the misses more slowly.
  spread = std::min(kMaxBudgetOffsetMs, 0.7 * spread + 0.3 * std::fabs(actual_ms - predicted_ms));
  offset = std::clamp(offset + 0.5 * (actual_ms - predicted_ms), -kMaxBudgetOffsetMs, kMaxBudgetOffsetMs);
  entry["offset_ms"] = offset;
  entry["spread_ms"] = spread;
  writeCache(cache_file, cache);
}

namespace {
std::string rangeKey(const std::string& path, const FieldSelector& field) {
  return "range|" + fileKey(path) + "|" + field.name + ":" +
         (field.magnitude ? std::string("mag") : std::to_string(field.component));
}
}  // namespace

std::optional<std::pair<double, double>> cachedBoundaryRange(const std::string& path, const FieldSelector& field) {
  if (!cacheable(path)) return std::nullopt;
  const nlohmann::json cache = readCache(cachePath());
  const std::string key = rangeKey(path, field);
  if (!cache.contains(key)) return std::nullopt;
  const nlohmann::json& r = cache[key];
  if (!r.is_array() || r.size() != 2 || !r[0].is_number() || !r[1].is_number()) return std::nullopt;
  const double lo = r[0].get<double>(), hi = r[1].get<double>();
  if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi) return std::nullopt;
  return std::make_pair(lo, hi);
}

void storeBoundaryRange(const std::string& path, const FieldSelector& field, std::pair<double, double> range) {
  if (!std::isfinite(range.first) || !std::isfinite(range.second) || !cacheable(path)) return;
  const std::string cache_file = cachePath();
  nlohmann::json cache = readCache(cache_file);
  cache[rangeKey(path, field)] = {range.first, range.second};
  writeCache(cache_file, cache);  // a lost write costs a decode later
}

}  // namespace gtn
