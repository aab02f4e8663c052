// gtn decode FILE.gtn [--level I | --ratio R] [--fields A,B] [--box ...] [--json]: decodes a stored level, or the
// mesh simplified to a ratio, into memory as `gtn export` does (points, tetrahedra, the fields), writes
// nothing, and reports the counts, the time taken and the tetrahedra decoded per second.
#include <sys/resource.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "cli/level_view.h"
#include "cli/threads.h"
#include "convert/import.h"
#include "format/decode_fields.h"
#include "format/gtn_reader.h"
#include "simplify/levels.h"

namespace gtn::cli {

namespace {
struct DecodeArgs {
  std::string input;
  size_t level = 0;
  double ratio = -1;                // < 0: not given
  std::vector<std::string> fields;  // empty: all
  std::string box;                  // --box XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX; empty: the whole level
  bool json = false;
};

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The largest resident set of this process so far, in bytes (0 where the system does not say).
uint64_t peakResidentBytes() {
  rusage u{};
  if (getrusage(RUSAGE_SELF, &u) != 0) return 0;
  return static_cast<uint64_t>(u.ru_maxrss) * 1024;  // Linux: kilobytes
}

nlohmann::json fieldsJson(const std::vector<Field>& fields, const char* location) {
  nlohmann::json out = nlohmann::json::array();
  for (const Field& f : fields)
    out.push_back({{"name", f.name},
                   {"location", location},
                   {"components", f.components},
                   {"type", scalarTypeName(f.type)},
                   {"values", f.itemCount()}});
  return out;
}

int runDecode(const DecodeArgs& a) {
  const Clock::time_point start = Clock::now();
  // Opened and decoded as `gtn export` does (cli/level_view.h).
  HeldWarnings damage;
  auto reader =
      openForView(a.input, "decode", "use 'gtn convert " + a.input + " -o FILE.gtn' to convert it first", damage);
  if (!reader.isOk()) return reportError(reader.status());
  GtnReader& r = **reader;
  TetMeshBuilder builder;
  SimplifyPlan plan;
  ViewRequest view;
  view.level = a.level;
  view.ratio = a.ratio;
  view.fields = a.fields;
  if (!a.box.empty()) {
    if (Status b = parseBox(a.box, &view); !b.isOk())
      return reportError(Status(b.code(), a.input + ": " + b.message()));
  }
  DecodeFields fields;
  const Clock::time_point decode_start = Clock::now();
  // A stored level of several pieces, whole: its pieces decoded in parallel straight into one mesh,
  // without the mesh stream that export's writers take.
  const bool whole_pieced = a.ratio < 0 && a.box.empty() && a.level < r.levels() && r.level(a.level).pieces.size() > 1;
  TetMesh pieced;
  Status st = Status::ok();
  if (whole_pieced) {
    plan.level = a.level;
    if (!a.fields.empty()) {
      auto selected = selectDecodeFields(r.level(a.level).header, a.fields, a.input, "--fields");
      if (selected.isOk()) fields = std::move(selected).value();
      else st = selected.status();
    }
    if (st.isOk()) {
      auto decoded = r.decodeLevelPieces(a.level, {}, a.fields.empty() ? nullptr : &fields);
      if (decoded.isOk()) pieced = std::move(decoded->mesh);
      else st = decoded.status();
    }
  } else {
    st = decodeView(r, a.input, view, builder, &fields, &plan);
  }
  if (!st.isOk()) {
    damage.flush(st);
    return reportError(st);
  }
  TetMesh& decoded_mesh = whole_pieced ? pieced : builder.mesh();
  if (!a.fields.empty()) dropUndecodedFields(decoded_mesh, fields);
  const double decode_s = secondsSince(decode_start);
  const double wall_s = secondsSince(start);
  damage.flush();

  const TetMesh& mesh = decoded_mesh;
  const double tets_per_second = decode_s > 0 ? static_cast<double>(mesh.numTets()) / decode_s : 0.0;
  if (a.json) {
    nlohmann::json j;
    j["input"] = a.input;
    j["bytes"] = r.file().bytes;
    j["level"] = plan.level;
    j["ratio"] = a.ratio >= 0 ? nlohmann::json(a.ratio) : nlohmann::json(nullptr);
    j["extra_merges"] = plan.extra_merges;
    j["points"] = mesh.numPoints();
    j["tets"] = mesh.numTets();
    nlohmann::json all = fieldsJson(mesh.point_fields, "point");
    for (nlohmann::json& f : fieldsJson(mesh.cell_fields, "cell")) all.push_back(std::move(f));
    j["fields"] = std::move(all);
    j["threads"] = ThreadLimit::active();
    j["wall_s"] = wall_s;
    j["decode_s"] = decode_s;
    j["tets_per_second"] = tets_per_second;
    j["peak_rss_bytes"] = peakResidentBytes();
    std::printf("%s\n", jsonText(j).c_str());
    return 0;
  }
  std::printf("%s: level %zu", a.input.c_str(), plan.level);
  if (a.ratio >= 0)
    std::printf(" + %llu merges on the fly (ratio %.4g)", static_cast<unsigned long long>(plan.extra_merges), a.ratio);
  std::printf("\n  points              %zu\n", mesh.numPoints());
  std::printf("  tetrahedra          %zu\n", mesh.numTets());
  for (const std::vector<Field>* list : {&mesh.point_fields, &mesh.cell_fields})
    for (const Field& f : *list)
      std::printf("  %s field %-12s %u x %s, %zu values\n", list == &mesh.point_fields ? "point" : "cell ",
                  f.name.c_str(), f.components, scalarTypeName(f.type), f.itemCount());
  std::printf("  decode              %.3f s (wall %.3f s with opening), %.0f tetrahedra per second, %d thread(s)\n",
              decode_s, wall_s, tets_per_second, ThreadLimit::active());
  std::printf("  peak resident       %.1f MB\n", static_cast<double>(peakResidentBytes()) / 1e6);
  return 0;
}
}  // namespace

Command addDecodeCommand(CLI::App& app) {
  auto args = std::make_shared<DecodeArgs>();
  CLI::App* sub = app.add_subcommand(
      "decode", "Decode a .gtn file into memory as export does, write nothing, report counts and time");
  sub->add_option("input", args->input, "Input .gtn file ('-' for standard input)")->required();
  CLI::Option* level = sub->add_option("--level", args->level, "Stored level to decode (0 = the lossless mesh)")
                           ->check(finiteAtLeastZero());
  CLI::Option* ratio =
      sub->add_option("--ratio", args->ratio,
                      "Simplification ratio: vertices merged away / vertices of level 0 that tetrahedra use (0 to 1)")
          ->check(ratioFromZeroToOne());
  level->excludes(ratio);
  sub->add_option("--fields", args->fields,
                  "Decode only these point or cell fields (names, comma-separated); the others are not decoded")
      ->delimiter(',');
  CLI::Option* box = addBoxOption(sub, &args->box);
  box->excludes(ratio);
  sub->add_flag("--json", args->json, "Print one JSON object on standard output");
  return {sub, [args] { return runDecode(*args); }};
}

}  // namespace gtn::cli
