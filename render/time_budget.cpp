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
#include "render/generic_renderer.h"
#include "render/stream_renderer.h"
#include "simplify/levels.h"

namespace gtn {

namespace {
// Bound of the learnt offset: beyond it the calibration is stale, not the run slower.
constexpr double kMaxOffsetMs = 2000.0;

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
         (o.sampling == Sampling::kFace ? "face" : "volume") + "|" + (generic ? "generic" : "integrated") +
         "|field " + o.field.name + "|" + o.field.whole;
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

// Interpolation through (x, y) points sorted by x, linear in x or in log x; beyond them, the nearest
// segment's slope (never decreasing).
double interpolate(const std::vector<std::pair<double, double>>& points, double n, bool logarithmic) {
  if (points.empty()) return 0;
  if (points.size() == 1) return points[0].first > 0 ? points[0].second * n / points[0].first : points[0].second;
  size_t i = 1;
  while (i + 1 < points.size() && points[i].first < n) ++i;
  const auto& [n0, m0] = points[i - 1];
  const auto& [n1, m1] = points[i];
  auto x = [&](double v) { return logarithmic ? std::log(std::max(v, 1.0)) : v; };
  const double slope = x(n1) > x(n0) ? std::max(0.0, (m1 - m0) / (x(n1) - x(n0))) : 0.0;
  return std::max(0.0, m0 + slope * (x(n) - x(n0)));
}
}  // namespace

StatusOr<LevelChoice> chooseForBudget(RenderInput& input, const std::string& path, double budget_ms,
                                      const RenderOptions& options, bool generic, double elapsed_ms,
                                      std::string* explanation, double* predicted_ms, std::string* shortfall) {
  if (!(budget_ms > 0)) return usageError("--budget-ms must be positive");
  const std::string key = "v4|" + cacheKey(path, options, generic);
  const std::string cache_file = cachePath();
  const bool cached = options.use_cache && cacheable(path);
  nlohmann::json cache = nlohmann::json::object();
  if (cached) {
    if (auto text = readWholeFile(cache_file, 1 << 24); text.isOk()) {
      cache = nlohmann::json::parse(text.value(), nullptr, false);
      if (!cache.is_object()) cache = nlohmann::json::object();
    }
  }
  // Measured (tetrahedra, ms) points, sorted by tetrahedra: whole runs, and decoding alone.
  std::vector<std::pair<double, double>> points, decode_points;
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
    if (entry->contains("decode_ms") && (*entry)["decode_ms"].is_array() &&
        (*entry)["decode_ms"].size() == points.size()) {
      for (size_t i = 0; i < points.size(); ++i) {
        const nlohmann::json& d = (*entry)["decode_ms"][i];
        if (!d.is_number()) {
          decode_points.clear();
          break;
        }
        decode_points.emplace_back(points[i].first, d.get<double>());
      }
    }
    if (decode_points.size() != points.size()) points.clear();  // an older entry: calibrate again
    source = "calibration read from " + cache_file;
  }
  // The floor: the coarsest level with every merge of its tree applied on the fly (merges, the
  // tetrahedra then rendered, and the time of the run), the cheapest plan there is.
  double floor_merges = 0, floor_tets = 0, floor_ms = 0;
  if (!points.empty() && entry->contains("floor") && (*entry)["floor"].is_object()) {
    const nlohmann::json& f = (*entry)["floor"];
    if (f.contains("merges") && f["merges"].is_number() && f.contains("tets") && f["tets"].is_number() &&
        f.contains("ms") && f["ms"].is_number()) {
      floor_merges = f["merges"].get<double>();
      floor_tets = f["tets"].get<double>();
      floor_ms = f["ms"].get<double>();
    }
  }
  // A calibration names the file's levels and its coarsest tree: another file under the same key
  // (replaced within the same second by one of the same size) is calibrated again, not planned with
  // them (a floor of more merges than the tree holds failed the run).
  if (!points.empty()) {
    bool same = true;
    for (const auto& [tets, ms] : points) {
      bool found = false;
      for (size_t i = 0; i < input.levels() && !found; ++i)
        found = static_cast<double>(input.levelHeader(i).tets) == tets;
      same &= found;
    }
    if (floor_merges > 0) {
      auto merges = floorMerges(input);
      same &= merges.isOk() && static_cast<double>(*merges) == floor_merges;
    }
    if (!same) {
      points.clear();
      decode_points.clear();
      floor_merges = floor_tets = floor_ms = 0;
    }
  }
  // What a real run costs beyond the calibration's timings, learnt from the budgeted runs since: a
  // run is a fresh process (cold memory, a new thread pool) that also writes the image, which the
  // calibration, timed in one warm process, does not see. At the coarse end this is most of the
  // error, and it adds rather than scales (blunt fin at 256x256: about 20 ms on runs of 30-60 ms).
  // And how far runs have scattered around the predictions (a moving mean of |actual - predicted|):
  // the plan keeps that much more room.
  double offset = 0, spread = 0;
  if (!points.empty() && entry->contains("offset_ms") && (*entry)["offset_ms"].is_number()) {
    const double v = (*entry)["offset_ms"].get<double>();
    if (std::fabs(v) <= kMaxOffsetMs) offset = v;
  }
  if (!points.empty() && entry->contains("spread_ms") && (*entry)["spread_ms"].is_number()) {
    const double v = (*entry)["spread_ms"].get<double>();
    if (v >= 0 && v <= kMaxOffsetMs) spread = v;
  }
  if (points.empty()) {
    // Levels timed: the coarsest, the finest with at most a sixteenth and a quarter of level 0's
    // tetrahedra, and level 0, so that every level's time is interpolated, not extrapolated; and
    // every level coarser than that sixteenth. There time stops following the tetrahedra (the rays
    // cost the most, and a much simplified boundary may cover fewer pixels: blunt fin's level 8
    // takes twice what level 9 and level 4 interpolate to), and those levels are cheap to time. A
    // first run of the coarsest level (not kept) warms the file and the thread pool.
    const size_t coarsest = input.levels() - 1;
    const uint64_t t0 = input.levelHeader(0).tets;
    std::vector<size_t> timed = {coarsest, 0};
    for (uint64_t divisor : {16, 4}) {
      for (size_t i = 0; i < input.levels(); ++i) {
        if (input.levelHeader(i).tets * divisor <= t0) {
          timed.push_back(i);
          if (divisor == 16)
            for (size_t j = i + 1; j < coarsest; ++j) timed.push_back(j);
          break;
        }
      }
    }
    std::sort(timed.begin(), timed.end());
    timed.erase(std::unique(timed.begin(), timed.end()), timed.end());
    // The warm-up run is timed too: what it takes beyond the warm run of the same level, plus writing
    // the image, is the first estimate of what a real run costs beyond the calibration (see offset).
    GTN_ASSIGN_OR_RETURN(const double cold_ms, timeLevel(input, coarsest, options, generic));
    double extra_ms = 0;
    {
      Image image;
      GTN_ASSIGN_OR_RETURN(const double warm_ms, timeLevel(input, coarsest, options, generic, &image));
      // Beside the cache, or (nothing cached) in the temporary directory.
      std::error_code ec;
      std::string probe = cache_file + ".probe.png";
      if (cached) {
        std::filesystem::create_directories(std::filesystem::path(cache_file).parent_path(), ec);
      } else {
        probe = (std::filesystem::temp_directory_path(ec) / ("gatun-render-probe-" + std::to_string(::getpid()) + ".png"))
                    .string();
      }
      const auto t0 = std::chrono::steady_clock::now();
      const Status written = writePng(probe, image);
      const double png_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      std::filesystem::remove(probe, ec);
      extra_ms = std::max(0.0, cold_ms - warm_ms) + (written.isOk() ? png_ms : 0.0);
    }
    offset = extra_ms;
    nlohmann::json tets = nlohmann::json::array(), ms = nlohmann::json::array(), dms = nlohmann::json::array();
    std::string names;
    for (size_t level : timed) {
      GTN_ASSIGN_OR_RETURN(double t, timeLevel(input, level, options, generic));
      GTN_ASSIGN_OR_RETURN(double d, timeDecode(input, level, options.field));
      const double n = static_cast<double>(input.levelHeader(level).tets);
      points.emplace_back(n, t);
      decode_points.emplace_back(n, std::min(d, t));
      tets.push_back(n);
      ms.push_back(t);
      dms.push_back(std::min(d, t));
      names += (names.empty() ? "" : ", ") + std::to_string(level);
    }
    nlohmann::json floor = nullptr;
    GTN_ASSIGN_OR_RETURN(const uint64_t tree_merges, floorMerges(input));
    if (tree_merges > 0) {
      LevelChoice all;
      all.merges = static_cast<int64_t>(input.levelHeader(coarsest).merges + tree_merges);
      uint64_t rendered = 0;
      GTN_ASSIGN_OR_RETURN(floor_ms, timeChoice(input, all, options, generic, nullptr, &rendered));
      floor_merges = static_cast<double>(tree_merges);
      floor_tets = static_cast<double>(rendered);
      floor = {{"merges", floor_merges}, {"tets", floor_tets}, {"ms", floor_ms}};
      names += " and " + std::to_string(coarsest) + " with " + std::to_string(tree_merges) + " merges of its tree";
    }
    if (cached) {
      cache[key] = {{"tets", tets}, {"ms", ms}, {"decode_ms", dms}, {"offset_ms", offset}, {"floor", floor}};
      std::error_code ec;
      std::filesystem::create_directories(std::filesystem::path(cache_file).parent_path(), ec);
      const std::string text = cache.dump(1, ' ', false, nlohmann::json::error_handler_t::replace);
      // A cache that cannot be written only costs a calibration next time.
      (void)writeBytesAtomically(cache_file, text.data(), text.size(), /*sync=*/false);
      source = "calibrated on levels " + names + ", cached in " + cache_file;
    } else if (!options.use_cache) {
      source = "calibrated on levels " + names + ", not cached (--no-cache)";
    } else {
      source = "calibrated on levels " + names + ", not cached (" + (path == "-" ? "standard input" : path) +
               " is no regular file)";
    }
  }
  std::sort(points.begin(), points.end());
  std::sort(decode_points.begin(), decode_points.end());
  // A whole run is interpolated in the logarithm of the tetrahedra: rendering has a large part that
  // depends on the pixels and the samples, not on the mesh, so halving a coarse level saves a
  // roughly constant time (blunt fin at 256x256: 25, 45, 72, 95 ms for 332, 468, 1189, 2499
  // tetrahedra), which a line through the calibrated levels misses by a factor of two. Decoding is
  // linear in the tetrahedra.
  auto whole = [&](double n) { return interpolate(points, n, true); };
  auto timedTets = [&](uint64_t n) {
    return std::any_of(points.begin(), points.end(), [&](const auto& p) { return p.first == static_cast<double>(n); });
  };
  auto decoding = [&](double n) { return std::min(whole(n), interpolate(decode_points, n, false)); };
  auto predict = [&](double n) { return std::max(0.0, offset + whole(n)); };
  // Level i with more merges: decoding level i is paid in full (plus the filter, a few percent); the
  // rest is that of a run of the tetrahedra left, interpolated between level i's and the next stored
  // level's counts by the merges.
  constexpr double kFilterCost = 1.05;
  auto predictMerged = [&](size_t i, double fraction) {
    const double n = static_cast<double>(input.levelHeader(i).tets);
    const double n_next = static_cast<double>(input.levelHeader(i + 1).tets);
    const double out = n + fraction * (n_next - n);
    return std::max(0.0, offset + kFilterCost * decoding(n) + whole(out) - decoding(out));
  };
  // What the run has spent before rendering (opening the input, this choice) counts against the
  // budget too.
  const double available = budget_ms - elapsed_ms;
  // The finest plan that fits: a stored level as is, else that level with on the fly merges towards
  // the next level, else the next level. Plans aim at 80% of what remains: the same run on this
  // 2-core machine scatters by +-15% from one minute to the next (blunt fin level 8: 40-53 ms, then
  // 57-82 ms), and the budget allows 10% more.
  constexpr double kMargin = 0.8;
  const double aim = std::min(kMargin * available, available - 1.5 * spread);
  // Beyond the coarsest level c: its tree's merges on the fly, the time interpolated (in the
  // logarithm of the tetrahedra left) between the stored level's and the floor's.
  const size_t coarsest = input.levels() - 1;
  const double n_c = static_cast<double>(input.levelHeader(coarsest).tets);
  const bool has_floor = floor_merges >= 1 && floor_tets >= 0 && floor_tets < n_c && floor_ms > 0 &&
                         floor_ms <= kMaxOffsetMs && input.hasMergeTree(coarsest);
  auto predictFloor = [&](double fraction) {
    const std::vector<std::pair<double, double>> ends = {{floor_tets, floor_ms}, {n_c, whole(n_c)}};
    return std::max(0.0, offset + interpolate(ends, n_c + fraction * (floor_tets - n_c), true));
  };
  LevelChoice choice;
  choice.level = static_cast<int>(coarsest);
  size_t chosen_level = coarsest;
  uint64_t extra = 0;
  double predicted = predict(n_c);
  // Level i with e of `span` merges on the fly, predicted by at(e / span).
  auto takeMerged = [&](size_t i, uint64_t span, uint64_t e, auto&& at) {
    extra = e;
    choice.level = -1;
    choice.merges = static_cast<int64_t>(input.levelHeader(i).merges + e);
    chosen_level = i;
    predicted = at(static_cast<double>(e) / static_cast<double>(span));
  };
  // The fewest of `span` merges on top of level i that fit, by bisection (the prediction falls with
  // the merges, up to the interpolation's kinks); false when even all of them do not fit.
  auto fewestFitting = [&](size_t i, uint64_t span, auto&& at) {
    if (span == 0 || at(1.0) > aim) return false;
    double lo = 0, hi = 1;
    for (int it = 0; it < 40; ++it) {
      const double mid = 0.5 * (lo + hi);
      (at(mid) <= aim ? hi : lo) = mid;
    }
    const uint64_t e = static_cast<uint64_t>(std::ceil(hi * static_cast<double>(span)));
    takeMerged(i, span, std::clamp<uint64_t>(e, 1, span), at);
    return true;
  };
  const uint64_t floor_span = has_floor ? static_cast<uint64_t>(floor_merges) : 0;
  if (has_floor) takeMerged(coarsest, floor_span, floor_span, predictFloor);  // until a plan fits: the cheapest
  for (size_t i = 0; i < input.levels(); ++i) {
    const double stored = predict(static_cast<double>(input.levelHeader(i).tets));
    if (stored <= aim) {
      choice = LevelChoice();
      choice.level = static_cast<int>(i);
      chosen_level = i;
      extra = 0;
      predicted = stored;
      break;
    }
    if (i + 1 >= input.levels()) {  // below the coarsest level: its own tree, down to the floor
      if (has_floor && fewestFitting(i, floor_span, predictFloor)) break;
      continue;
    }
    if (!input.hasMergeTree(i)) continue;
    if (input.levelHeader(i + 1).merges <= input.levelHeader(i).merges) continue;  // not coarser: nothing between
    // Between two timed levels the next one is the plan: at the coarse end the time falls in steps
    // with the merges (blunt fin, level 8 plus 32 of the 41 merges to level 9: 24 ms; plus 40: 12
    // ms), so an interpolation would promise what the run then misses.
    if (timedTets(input.levelHeader(i).tets) && timedTets(input.levelHeader(i + 1).tets)) continue;
    const uint64_t span = input.levelHeader(i + 1).merges - input.levelHeader(i).merges;
    if (fewestFitting(i, span, [&](double fraction) { return predictMerged(i, fraction); })) break;
  }
  std::string model;
  for (size_t i = 0; i < points.size(); ++i) {
    char p[96];
    std::snprintf(p, sizeof p, "%s%.0f tets %.1f ms (decoding %.1f)", model.empty() ? "" : ", ", points[i].first,
                  points[i].second, decode_points[i].second);
    model += p;
  }
  if (has_floor) {
    char p[128];
    std::snprintf(p, sizeof p, ", level %zu with %.0f merges of its tree %.0f tets %.1f ms", coarsest, floor_merges,
                  floor_tets, floor_ms);
    model += p;
  }
  char buf[1024];
  std::snprintf(buf, sizeof buf,
                "%s; measured %s, learnt offset %+.1f ms, spread %.1f ms; level %zu (%llu tetrahedra, %llu merges) + %llu merges on the fly "
                "predicted %.1f ms + %.1f ms already spent for a budget of %.1f ms%s",
                source.c_str(), model.c_str(), offset, spread, chosen_level,
                static_cast<unsigned long long>(input.levelHeader(chosen_level).tets),
                static_cast<unsigned long long>(input.levelHeader(chosen_level).merges),
                static_cast<unsigned long long>(extra), predicted, elapsed_ms, budget_ms,
                predicted > available ? " (the cheapest plan; the budget cannot be met)" : "");
  *explanation = buf;
  if (predicted_ms) *predicted_ms = predicted;
  if (shortfall) {
    shortfall->clear();
    if (predicted > available) {
      std::snprintf(buf, sizeof buf,
                    "--budget-ms %g cannot be met: the cheapest plan that still shows the mesh, level %zu + %llu merges "
                    "on the fly, is predicted at %.1f ms (%.1f ms already spent); rendering it",
                    budget_ms, chosen_level, static_cast<unsigned long long>(extra), predicted, elapsed_ms);
      *shortfall = buf;
    }
  }
  return choice;
}

void recordBudgetRun(const std::string& path, const RenderOptions& options, bool generic, double predicted_ms,
                     double actual_ms) {
  if (!(predicted_ms > 0) || !(actual_ms > 0) || !options.use_cache || !cacheable(path)) return;
  const std::string key = "v4|" + cacheKey(path, options, generic);
  const std::string cache_file = cachePath();
  auto text = readWholeFile(cache_file, 1 << 24);
  if (!text.isOk()) return;
  nlohmann::json cache = nlohmann::json::parse(text.value(), nullptr, false);
  if (!cache.is_object() || !cache.contains(key) || !cache[key].is_object()) return;
  nlohmann::json& entry = cache[key];
  double offset = entry.contains("offset_ms") && entry["offset_ms"].is_number() ? entry["offset_ms"].get<double>() : 0.0;
  if (!(std::fabs(offset) <= kMaxOffsetMs)) offset = 0;
  double spread = entry.contains("spread_ms") && entry["spread_ms"].is_number() ? entry["spread_ms"].get<double>() : 0.0;
  if (!(spread >= 0 && spread <= kMaxOffsetMs)) spread = 0;
  // Half way towards what this run says, so that one outlier does not swing it; the spread follows
  // the misses more slowly.
  spread = std::min(kMaxOffsetMs, 0.7 * spread + 0.3 * std::fabs(actual_ms - predicted_ms));
  offset = std::clamp(offset + 0.5 * (actual_ms - predicted_ms), -kMaxOffsetMs, kMaxOffsetMs);
  entry["offset_ms"] = offset;
  entry["spread_ms"] = spread;
  const std::string out = cache.dump(1, ' ', false, nlohmann::json::error_handler_t::replace);
  (void)writeBytesAtomically(cache_file, out.data(), out.size(), /*sync=*/false);
}

namespace {
std::string rangeKey(const std::string& path, const FieldSelector& field) {
  return "range|" + fileKey(path) + "|" + field.name + ":" +
         (field.magnitude ? std::string("mag") : std::to_string(field.component));
}
}  // namespace

std::optional<std::pair<double, double>> cachedBoundaryRange(const std::string& path, const FieldSelector& field) {
  if (!cacheable(path)) return std::nullopt;
  auto text = readWholeFile(cachePath(), 1 << 24);
  if (!text.isOk()) return std::nullopt;
  const nlohmann::json cache = nlohmann::json::parse(text.value(), nullptr, false);
  const std::string key = rangeKey(path, field);
  if (!cache.is_object() || !cache.contains(key)) return std::nullopt;
  const nlohmann::json& r = cache[key];
  if (!r.is_array() || r.size() != 2 || !r[0].is_number() || !r[1].is_number()) return std::nullopt;
  const double lo = r[0].get<double>(), hi = r[1].get<double>();
  if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi) return std::nullopt;
  return std::make_pair(lo, hi);
}

void storeBoundaryRange(const std::string& path, const FieldSelector& field, std::pair<double, double> range) {
  if (!std::isfinite(range.first) || !std::isfinite(range.second) || !cacheable(path)) return;
  const std::string cache_file = cachePath();
  nlohmann::json cache = nlohmann::json::object();
  if (auto text = readWholeFile(cache_file, 1 << 24); text.isOk()) {
    cache = nlohmann::json::parse(text.value(), nullptr, false);
    if (!cache.is_object()) cache = nlohmann::json::object();
  }
  cache[rangeKey(path, field)] = {range.first, range.second};
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(cache_file).parent_path(), ec);
  const std::string out = cache.dump(1, ' ', false, nlohmann::json::error_handler_t::replace);
  (void)writeBytesAtomically(cache_file, out.data(), out.size(), /*sync=*/false);  // a lost write costs a decode later
}

}  // namespace gtn
