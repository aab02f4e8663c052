// gtn info INPUT... [--split 5|6] [--weld] [--time-step N] [--json] [--merge-tree] [--plot FILE.png]: what a mesh holds.
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "cli/merge_tree_plot.h"
#include "convert/import.h"
#include "format/file_io.h"
#include "format/gtn_reader.h"
#include "mesh/mesh_stats.h"
#include "validate/info.h"

namespace gtn::cli {

namespace {
struct InfoArgs {
  std::vector<std::string> inputs;
  int split = 6;
  bool weld = false;
  int time_step = 0;
  bool json = false;
  bool merge_tree = false;
  std::string plot;  // --plot FILE.png
};

void printText(const std::string& name, const MeshStats& s, const ImportReport& r, const TetMesh& mesh) {
  std::printf("%s\n", name.c_str());
  std::printf("  points              %llu (%s)\n", static_cast<unsigned long long>(s.points),
              scalarTypeName(mesh.coord_type));
  std::printf("  tetrahedra          %llu\n", static_cast<unsigned long long>(s.tets));
  std::printf("  faces               %llu\n", static_cast<unsigned long long>(s.faces));
  std::printf("  boundary faces      %llu\n", static_cast<unsigned long long>(s.boundary_faces));
  std::printf("  non-manifold faces  %llu\n", static_cast<unsigned long long>(s.non_manifold_faces));
  std::printf("  inverted            %llu\n", static_cast<unsigned long long>(s.inverted));
  std::printf("  zero volume         %llu\n", static_cast<unsigned long long>(s.zero_volume));
  std::printf("  unreferenced points %llu\n", static_cast<unsigned long long>(s.unreferenced_points));
  std::printf("  coincident points   %llu\n", static_cast<unsigned long long>(s.coincident_points));
  std::printf("  bounding box        [%.9g, %.9g] x [%.9g, %.9g] x [%.9g, %.9g]\n", s.bbox_min[0], s.bbox_max[0],
              s.bbox_min[1], s.bbox_max[1], s.bbox_min[2], s.bbox_max[2]);
  std::printf("  volume              min %.6g, max %.6g, total %.9g\n", s.min_volume, s.max_volume, s.total_volume);
  for (const FieldStats& f : s.fields) {
    char range[80] = "no finite value";
    if (f.has_range) std::snprintf(range, sizeof range, "range [%.9g, %.9g]", f.min, f.max);
    std::printf("  %s field %-12s %u x %s, %s%s\n", f.per_cell ? "cell " : "point", f.name.c_str(), f.components,
                scalarTypeName(f.type), range,
                f.non_finite ? (", " + std::to_string(f.non_finite) + " non-finite").c_str() : "");
  }
  for (const auto& [k, v] : mesh.metadata) std::printf("  metadata %s = %s\n", k.c_str(), v.c_str());
  if (r.flipped) std::printf("  flipped on import   %zu\n", r.flipped);
  if (r.dropped_cells) std::printf("  dropped on import   %zu\n", r.dropped_cells);
  if (r.welded_points)
    std::printf("  welded points       %zu (collapsed tetrahedra %zu)\n", r.welded_points, r.collapsed_tets);
  if (r.steiner_points) std::printf("  Steiner points      %zu\n", r.steiner_points);
}

// What a .gtn file holds: the container (version, provenance, levels, bytes per section, bits per
// tetrahedron of level 0) and the statistics of level 0 as decoded by the streaming decoder.
int runGtnInfo(const InfoArgs& a) {
  if (a.inputs.size() != 1) return reportError(usageError("gtn info reads one .gtn file at a time"));
  const std::string& input = a.inputs[0];
  auto reader = GtnReader::open(input);  // full validation: every chunk, checksum, order, trailer
  if (!reader.isOk()) return reportError(reader.status());
  GtnReader& r = **reader;
  TetMeshBuilder builder;
  DecodeStats decode_stats;
  Status st = r.decodeLevel(0, builder, &decode_stats);
  if (!st.isOk()) return reportError(st);
  const TetMesh& mesh = builder.mesh();
  const MeshStats stats = computeMeshStats(mesh);
  const GtnFileInfo& f = r.file();

  const LevelZeroBytes bytes = levelZeroBytes(r);
  const double tets = static_cast<double>(r.level(0).header.tets);
  const std::string version = std::to_string(f.major) + "." + std::to_string(f.minor);

  if (!a.plot.empty()) {
    if (a.plot == input || sameFile(input, a.plot))
      return reportError(usageError(a.plot + ": --plot: the output would overwrite the input"));
    Status plotted = plotMergeTree(r, a.plot);
    if (!plotted.isOk()) return reportError(plotted);
  }
  if (a.json) {
    auto j = gtnInfoJson(r, mesh, stats, decode_stats, a.merge_tree);
    if (!j.isOk()) return reportError(j.status());
    j.value()["input"] = a.inputs;
    std::printf("%s\n", jsonText(j.value()).c_str());
    return 0;
  }
  std::printf("%s: .gtn format %s, %llu bytes, %zu level(s)%s\n", input.c_str(), version.c_str(),
              static_cast<unsigned long long>(f.bytes), r.levels(), f.has_directory ? ", with directory" : "");
  std::printf("  written by          %s\n", f.header.tool_version.c_str());
  std::printf("  command line        %s\n", f.header.command_line.c_str());
  for (size_t i = 0; i < r.levels(); ++i) {
    const GtnLevelInfo& l = r.level(i);
    const std::string pieces = l.pieces.size() > 1 ? ", " + std::to_string(l.pieces.size()) + " pieces" : "";
    const std::string names = l.base ? ", names level " + std::to_string(i + 1) + "'s vertices" : "";
    std::printf("  level %-3zu           %llu points, %llu tetrahedra, %llu merges (ratio %.4g), %llu bytes%s%s%s\n", i,
                static_cast<unsigned long long>(l.header.points), static_cast<unsigned long long>(l.header.tets),
                static_cast<unsigned long long>(l.header.merges), l.ratio, static_cast<unsigned long long>(l.bytes),
                pieces.c_str(), l.has_merge_tree ? ", merge tree" : "", names.c_str());
  }
  for (const GtnSection& s : r.sections())
    std::printf("  section %-22s %llu bytes\n", s.name.c_str(), static_cast<unsigned long long>(s.bytes));
  if (tets > 0)
    std::printf("  bits per tetrahedron connectivity %.3f, geometry %.3f, fields %.3f, merge tree %.3f, total %.3f\n",
                8.0 * bytes.connectivity / tets, 8.0 * bytes.geometry / tets, 8.0 * bytes.fields / tets,
                8.0 * bytes.merge_tree / tets, 8.0 * bytes.total / tets);
  std::printf("  peak live vertices  %llu\n", static_cast<unsigned long long>(decode_stats.peak_live_vertices));
  if (a.merge_tree) {
    auto mt = mergeTreeReport(r);
    if (!mt.isOk()) return reportError(mt.status());
    if (!mt.value()) std::printf("  merge tree          none\n");
    else std::printf("  merge tree (level 0)\n%s", mergeTreeReportText(*mt.value(), "    ").c_str());
  }
  printText(input + " (level 0, decoded)", stats, ImportReport{}, mesh);
  return 0;
}

int runInfo(const InfoArgs& a) {
  for (const std::string& in : a.inputs)
    // Standard input cannot be sniffed without consuming it: only a .gtn file is read from a pipe.
    if (in == "-" || detectInputFormat(in) == InputFormat::kGtn) return runGtnInfo(a);
  if (!a.plot.empty())
    return reportError(usageError(a.inputs[0] + ": --plot draws the merge tree of a .gtn file; a mesh has none"));
  ImportOptions options;
  options.split = a.split;
  options.weld = a.weld;
  options.exodus_time_step = a.time_step;
  auto imported = importMesh(a.inputs, options);
  if (!imported.isOk()) return reportError(imported.status());
  for (const std::string& w : imported->report.warnings) warnAbout(a.inputs[0], w);
  if (a.merge_tree) warn(a.inputs[0] + ": --merge-tree describes the merge tree of a .gtn file; a mesh has none");
  const MeshStats stats = computeMeshStats(imported->mesh);
  if (a.json) {
    nlohmann::json j = meshInfoJson(stats, imported->report, imported->mesh);
    j["input"] = a.inputs;
    std::printf("%s\n", jsonText(j).c_str());
  } else {
    printText(a.inputs[0], stats, imported->report, imported->mesh);
  }
  return 0;
}
}  // namespace

Command addInfoCommand(CLI::App& app) {
  auto args = std::make_shared<InfoArgs>();
  CLI::App* sub = app.add_subcommand("info", "Print what a mesh holds: counts, orientation, bounding box, fields");
  sub->add_option("inputs", args->inputs, "Input files (as for convert), or one .gtn file ('-': standard input)")
      ->required();
  sub->add_option("--split", args->split, "Hexahedra into 5 or 6 tetrahedra")->check(CLI::IsMember({5, 6}));
  sub->add_flag("--weld", args->weld, "merge bit-identical points (seams between PLOT3D blocks or VTK pieces)");
  sub->add_option("--time-step", args->time_step,
                  "Exodus II: the time step (1, 2, ...) whose variables become fields (default: the last)")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--json", args->json, "Print one JSON object on standard output");
  sub->add_flag("--merge-tree", args->merge_tree,
                ".gtn: level 0's merge tree as a table (merges, roots, depth, fan-out, error quantiles; per "
                "stored level: ratio, points, tetrahedra, bytes, merges, largest error)");
  sub->add_option("--plot", args->plot,
                  ".gtn: draw level 0's merge error against the simplification ratio, stored levels marked, "
                  "as a PNG image (needs gnuplot)");
  return {sub, [args] { return runInfo(*args); }};
}

}  // namespace gtn::cli
