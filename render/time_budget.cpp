#include "render/time_budget.h"

#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "format/file_io.h"
#include "render/generic_renderer.h"
#include "render/stream_renderer.h"

namespace gtn {

namespace {
// Bounds of the learnt speed factor: beyond them the calibration is stale, not the machine busy.
constexpr double kMinScale = 0.2, kMaxScale = 5.0;

std::string cachePath() {
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  std::string base;
  if (xdg && *xdg) base = xdg;
  else if (const char* home = std::getenv("HOME"); home && *home) base = std::string(home) + "/.cache";
  else base = std::filesystem::temp_directory_path().string();
  return base + "/gatun/render-calibration.json";
}

std::string cacheKey(const std::string& path, const RenderOptions& o, bool generic) {
  struct stat st {};
  std::string abs = path;
  std::error_code ec;
  const auto p = std::filesystem::absolute(path, ec);
  if (!ec) abs = p.string();
  if (::stat(path.c_str(), &st) != 0) st = {};
  return abs + "|" + std::to_string(st.st_size) + "|" + std::to_string(st.st_mtime) + "|" +
         std::to_string(o.camera.width) + "x" + std::to_string(o.camera.height) + "|" +
         (o.sampling == Sampling::kFace ? "face" : "volume") + "|" + (generic ? "generic" : "integrated");
}

// Time of one end-to-end render of stored level `level` (decode + render, image discarded).
StatusOr<double> timeLevel(RenderInput& input, size_t level, const RenderOptions& options, bool generic) {
  LevelChoice choice;
  choice.level = static_cast<int>(level);
  GTN_ASSIGN_OR_RETURN(ResolvedLevel resolved, input.resolve(choice));
  const auto t0 = std::chrono::steady_clock::now();
  RenderOptions fixed = options;  // as the real run will: its view fixing is part of the time
  GTN_RETURN_IF_ERROR(input.fixView(resolved, &fixed));
  if (generic) {
    TetMeshBuilder builder;
    GTN_RETURN_IF_ERROR(input.stream(resolved, builder));
    GTN_ASSIGN_OR_RETURN(Image image, renderGeneric(builder.header(), builder.mesh(), builder.boundary(), fixed));
    (void)image;
  } else {
    StreamRenderer renderer(fixed);
    GTN_RETURN_IF_ERROR(input.stream(resolved, renderer));
  }
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

StatusOr<LevelChoice> chooseForBudget(RenderInput& input, const std::string& path, double budget_ms,
                                      const RenderOptions& options, bool generic, double elapsed_ms,
                                      std::string* explanation, double* predicted_ms) {
  if (!(budget_ms > 0)) return usageError("--budget-ms must be positive");
  const std::string key = "v2|" + cacheKey(path, options, generic);
  const std::string cache_file = cachePath();
  nlohmann::json cache = nlohmann::json::object();
  if (auto text = readWholeFile(cache_file, 1 << 24); text.isOk()) {
    cache = nlohmann::json::parse(text.value(), nullptr, false);
    if (!cache.is_object()) cache = nlohmann::json::object();
  }
  // Measured (tetrahedra, ms) points, sorted by tetrahedra.
  std::vector<std::pair<double, double>> points;
  std::string source;
  const nlohmann::json* entry = cache.contains(key) ? &cache[key] : nullptr;
  if (entry && entry->is_object() && entry->contains("tets") && entry->contains("ms") && (*entry)["tets"].is_array() &&
      (*entry)["ms"].is_array() && (*entry)["tets"].size() == (*entry)["ms"].size() && !(*entry)["tets"].empty()) {
    for (size_t i = 0; i < (*entry)["tets"].size(); ++i) {
      const nlohmann::json& t = (*entry)["tets"][i];
      const nlohmann::json& m = (*entry)["ms"][i];
      if (!t.is_number() || !m.is_number()) {
        points.clear();
        break;
      }
      points.emplace_back(t.get<double>(), m.get<double>());
    }
    source = "calibration read from " + cache_file;
  }
  // The machine's speed now against the calibration's, learnt from the budgeted runs since.
  double scale = 1;
  if (!points.empty() && entry->contains("scale") && (*entry)["scale"].is_number()) {
    const double v = (*entry)["scale"].get<double>();
    if (v >= kMinScale && v <= kMaxScale) scale = v;
  }
  if (points.empty()) {
    // Levels timed: the coarsest, the finest with at most a sixteenth and a quarter of level 0's
    // tetrahedra, and level 0, so that every level's time is interpolated, not extrapolated. A first
    // run of the coarsest level (not kept) warms the file and the thread pool.
    const size_t coarsest = input.levels() - 1;
    const uint64_t t0 = input.levelHeader(0).tets;
    std::vector<size_t> timed = {coarsest, 0};
    for (uint64_t divisor : {16, 4}) {
      for (size_t i = 0; i < input.levels(); ++i) {
        if (input.levelHeader(i).tets * divisor <= t0) {
          timed.push_back(i);
          break;
        }
      }
    }
    std::sort(timed.begin(), timed.end());
    timed.erase(std::unique(timed.begin(), timed.end()), timed.end());
    GTN_RETURN_IF_ERROR(timeLevel(input, coarsest, options, generic).status());
    nlohmann::json tets = nlohmann::json::array(), ms = nlohmann::json::array();
    std::string names;
    for (size_t level : timed) {
      GTN_ASSIGN_OR_RETURN(double t, timeLevel(input, level, options, generic));
      const double n = static_cast<double>(input.levelHeader(level).tets);
      points.emplace_back(n, t);
      tets.push_back(n);
      ms.push_back(t);
      names += (names.empty() ? "" : ", ") + std::to_string(level);
    }
    cache[key] = {{"tets", tets}, {"ms", ms}};
    std::error_code ec;
    std::filesystem::create_directories(std::filesystem::path(cache_file).parent_path(), ec);
    const std::string text = cache.dump(1);
    // A cache that cannot be written only costs a calibration next time.
    (void)writeBytesAtomically(cache_file, text.data(), text.size());
    source = "calibrated on levels " + names + ", cached in " + cache_file;
  }
  std::sort(points.begin(), points.end());
  // Piecewise linear in the tetrahedra decoded between measured levels; beyond them, the nearest
  // segment's slope (never decreasing).
  auto predict = [&](double n) {
    if (points.size() == 1)
      return scale * (points[0].first > 0 ? points[0].second * n / points[0].first : points[0].second);
    size_t i = 1;
    while (i + 1 < points.size() && points[i].first < n) ++i;
    const auto& [n0, m0] = points[i - 1];
    const auto& [n1, m1] = points[i];
    const double slope = n1 > n0 ? std::max(0.0, (m1 - m0) / (n1 - n0)) : 0.0;
    return scale * std::max(0.0, m0 + slope * (n - n0));
  };
  // What the run has spent before rendering (opening the input, this choice) counts against the
  // budget too.
  const double available = budget_ms - elapsed_ms;
  LevelChoice choice;
  choice.level = static_cast<int>(input.levels() - 1);
  for (size_t i = 0; i < input.levels(); ++i) {
    if (predict(static_cast<double>(input.levelHeader(i).tets)) <= available) {
      choice.level = static_cast<int>(i);
      break;
    }
  }
  const double predicted = predict(static_cast<double>(input.levelHeader(choice.level).tets));
  std::string model;
  for (const auto& [n, m] : points) {
    char p[64];
    std::snprintf(p, sizeof p, "%s%.0f tets %.1f ms", model.empty() ? "" : ", ", n, m);
    model += p;
  }
  char buf[1024];
  std::snprintf(buf, sizeof buf,
                "%s; measured %s, speed factor %.2f; level %d (%llu tetrahedra, %llu merges) predicted %.1f ms + %.1f ms already spent "
                "for a budget of %.1f ms%s",
                source.c_str(), model.c_str(), scale, choice.level,
                static_cast<unsigned long long>(input.levelHeader(choice.level).tets),
                static_cast<unsigned long long>(input.levelHeader(choice.level).merges), predicted, elapsed_ms,
                budget_ms, predicted > available ? " (the coarsest level; the budget cannot be met)" : "");
  *explanation = buf;
  if (predicted_ms) *predicted_ms = predicted;
  return choice;
}

void recordBudgetRun(const std::string& path, const RenderOptions& options, bool generic, double predicted_ms,
                     double actual_ms) {
  if (!(predicted_ms > 0) || !(actual_ms > 0)) return;
  const std::string key = "v2|" + cacheKey(path, options, generic);
  const std::string cache_file = cachePath();
  auto text = readWholeFile(cache_file, 1 << 24);
  if (!text.isOk()) return;
  nlohmann::json cache = nlohmann::json::parse(text.value(), nullptr, false);
  if (!cache.is_object() || !cache.contains(key) || !cache[key].is_object()) return;
  nlohmann::json& entry = cache[key];
  double scale = entry.contains("scale") && entry["scale"].is_number() ? entry["scale"].get<double>() : 1.0;
  if (!(scale >= kMinScale && scale <= kMaxScale)) scale = 1;
  // Half way (geometrically) towards what this run says, so that one outlier does not swing it.
  scale = std::clamp(scale * std::sqrt(actual_ms / predicted_ms), kMinScale, kMaxScale);
  entry["scale"] = scale;
  const std::string out = cache.dump(1);
  (void)writeBytesAtomically(cache_file, out.data(), out.size());
}

}  // namespace gtn
