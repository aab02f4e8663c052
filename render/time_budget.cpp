#include "render/time_budget.h"

#include <sys/stat.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "format/file_io.h"
#include "render/generic_renderer.h"
#include "render/stream_renderer.h"

namespace gtn {

namespace {
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
                                      const RenderOptions& options, bool generic, std::string* explanation) {
  if (!(budget_ms > 0)) return usageError("--budget-ms must be positive");
  const std::string key = cacheKey(path, options, generic);
  const std::string cache_file = cachePath();
  nlohmann::json cache = nlohmann::json::object();
  if (auto text = readWholeFile(cache_file, 1 << 24); text.isOk()) {
    cache = nlohmann::json::parse(text.value(), nullptr, false);
    if (!cache.is_object()) cache = nlohmann::json::object();
  }
  double fixed_ms = 0, per_tet_ms = 0;
  std::string source;
  if (cache.contains(key) && cache[key].is_object() && cache[key].contains("fixed_ms") &&
      cache[key].contains("per_tet_ms")) {
    fixed_ms = cache[key]["fixed_ms"].get<double>();
    per_tet_ms = cache[key]["per_tet_ms"].get<double>();
    source = "calibration read from " + cache_file;
  } else {
    const size_t coarsest = input.levels() - 1;
    // The second point: the finest level with at most a sixteenth of level 0's tetrahedra.
    size_t mid = 0;
    const uint64_t t0 = input.levelHeader(0).tets;
    for (size_t i = 0; i < input.levels(); ++i)
      if (input.levelHeader(i).tets * 16 <= t0) {
        mid = i;
        break;
      }
    if (mid == 0 && input.levels() > 1) mid = coarsest;
    GTN_ASSIGN_OR_RETURN(double t_mid, timeLevel(input, mid, options, generic));
    const double n_mid = static_cast<double>(input.levelHeader(mid).tets);
    if (coarsest != mid) {
      GTN_ASSIGN_OR_RETURN(double t_low, timeLevel(input, coarsest, options, generic));
      const double n_low = static_cast<double>(input.levelHeader(coarsest).tets);
      per_tet_ms = n_mid > n_low ? std::max(0.0, (t_mid - t_low) / (n_mid - n_low)) : 0.0;
      fixed_ms = std::max(0.0, t_low - per_tet_ms * n_low);
    } else {
      per_tet_ms = n_mid > 0 ? t_mid / n_mid : 0.0;
    }
    if (per_tet_ms <= 0) per_tet_ms = 1e-6;
    cache[key] = {{"fixed_ms", fixed_ms}, {"per_tet_ms", per_tet_ms}};
    std::error_code ec;
    std::filesystem::create_directories(std::filesystem::path(cache_file).parent_path(), ec);
    const std::string text = cache.dump(1);
    // A cache that cannot be written only costs a calibration next time.
    (void)writeBytesAtomically(cache_file, text.data(), text.size());
    source = "calibrated on levels " + std::to_string(mid) + " and " + std::to_string(coarsest) + ", cached in " +
             cache_file;
  }
  LevelChoice choice;
  choice.level = static_cast<int>(input.levels() - 1);
  for (size_t i = 0; i < input.levels(); ++i) {
    if (fixed_ms + per_tet_ms * static_cast<double>(input.levelHeader(i).tets) <= budget_ms) {
      choice.level = static_cast<int>(i);
      break;
    }
  }
  const double predicted = fixed_ms + per_tet_ms * static_cast<double>(input.levelHeader(choice.level).tets);
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "%s; model %.2f ms + %.3g ms per tetrahedron decoded; level %d (%llu tetrahedra, %llu merges) "
                "predicted %.1f ms for a budget of %.1f ms%s",
                source.c_str(), fixed_ms, per_tet_ms, choice.level,
                static_cast<unsigned long long>(input.levelHeader(choice.level).tets),
                static_cast<unsigned long long>(input.levelHeader(choice.level).merges), predicted, budget_ms,
                predicted > budget_ms ? " (the coarsest level; the budget cannot be met)" : "");
  *explanation = buf;
  return choice;
}

}  // namespace gtn
