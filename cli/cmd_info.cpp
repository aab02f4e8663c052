// gtn info INPUT... [--split 5|6] [--weld] [--json]: what a mesh holds.
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "convert/import.h"
#include "mesh/mesh_stats.h"

namespace gtn::cli {

namespace {
struct InfoArgs {
  std::vector<std::string> inputs;
  int split = 6;
  bool weld = false;
  bool json = false;
};

nlohmann::json statsToJson(const MeshStats& s, const ImportReport& r, const TetMesh& mesh) {
  nlohmann::json j;
  j["points"] = s.points;
  j["tets"] = s.tets;
  j["faces"] = s.faces;
  j["boundary_faces"] = s.boundary_faces;
  j["non_manifold_faces"] = s.non_manifold_faces;
  j["inverted"] = s.inverted;
  j["zero_volume"] = s.zero_volume;
  j["unreferenced_points"] = s.unreferenced_points;
  j["coincident_points"] = s.coincident_points;
  j["coordinate_type"] = scalarTypeName(mesh.coord_type);
  j["bbox"] = {{"min", {s.bbox_min[0], s.bbox_min[1], s.bbox_min[2]}},
               {"max", {s.bbox_max[0], s.bbox_max[1], s.bbox_max[2]}}};
  j["volume"] = {{"min", s.min_volume}, {"max", s.max_volume}, {"total", s.total_volume}};
  nlohmann::json fields = nlohmann::json::array();
  for (const FieldStats& f : s.fields) {
    fields.push_back({{"name", f.name},
                      {"components", f.components},
                      {"type", scalarTypeName(f.type)},
                      {"location", f.per_cell ? "cell" : "point"},
                      {"min", f.min},
                      {"max", f.max},
                      {"non_finite", f.non_finite}});
  }
  j["fields"] = fields;
  nlohmann::json meta = nlohmann::json::object();
  for (const auto& [k, v] : mesh.metadata) meta[k] = v;
  j["metadata"] = meta;
  j["import"] = {{"flipped", r.flipped},
                 {"zero_volume", r.zero_volume},
                 {"dropped_cells", r.dropped_cells},
                 {"welded_points", r.welded_points},
                 {"collapsed_tets", r.collapsed_tets},
                 {"steiner_points", r.steiner_points},
                 {"warnings", r.warnings}};
  return j;
}

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
    std::printf("  %s field %-12s %u x %s, range [%.9g, %.9g]%s\n", f.per_cell ? "cell " : "point", f.name.c_str(),
                f.components, scalarTypeName(f.type), f.min, f.max,
                f.non_finite ? (", " + std::to_string(f.non_finite) + " non-finite").c_str() : "");
  }
  for (const auto& [k, v] : mesh.metadata) std::printf("  metadata %s = %s\n", k.c_str(), v.c_str());
  if (r.flipped) std::printf("  flipped on import   %zu\n", r.flipped);
  if (r.dropped_cells) std::printf("  dropped on import   %zu\n", r.dropped_cells);
  if (r.welded_points) std::printf("  welded points       %zu (collapsed tetrahedra %zu)\n", r.welded_points, r.collapsed_tets);
  if (r.steiner_points) std::printf("  Steiner points      %zu\n", r.steiner_points);
}

int runInfo(const InfoArgs& a) {
  ImportOptions options;
  options.split = a.split;
  options.weld = a.weld;
  auto imported = importMesh(a.inputs, options);
  if (!imported.isOk()) return reportError(imported.status());
  for (const std::string& w : imported->report.warnings) warn(a.inputs[0] + ": " + w);
  const MeshStats stats = computeMeshStats(imported->mesh);
  if (a.json) {
    nlohmann::json j = statsToJson(stats, imported->report, imported->mesh);
    j["input"] = a.inputs;
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    printText(a.inputs[0], stats, imported->report, imported->mesh);
  }
  return 0;
}
}  // namespace

Command addInfoCommand(CLI::App& app) {
  auto args = std::make_shared<InfoArgs>();
  CLI::App* sub = app.add_subcommand("info", "Print what a mesh holds: counts, orientation, bounding box, fields");
  sub->add_option("inputs", args->inputs, "Input files (as for convert)")->required();
  sub->add_option("--split", args->split, "Hexahedra into 5 or 6 tetrahedra")->check(CLI::IsMember({5, 6}));
  sub->add_flag("--weld", args->weld, "PLOT3D: merge bit-identical points");
  sub->add_flag("--json", args->json, "Print one JSON object on standard output");
  return {sub, [args] { return runInfo(*args); }};
}

}  // namespace gtn::cli
