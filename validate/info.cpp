#include "validate/info.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "simplify/levels.h"

namespace gtn {

namespace {
const char* const kQuantileNames[9] = {"min", "p01", "p10", "p25", "p50", "p75", "p90", "p99", "max"};

std::string format(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}
std::string number(uint64_t v) { return std::to_string(v); }
std::string general(double v) { return format("%.6g", v); }
std::string padRight(const std::string& s, size_t width) {
  return s.size() >= width ? s : s + std::string(width - s.size(), ' ');
}
std::string padLeft(const std::string& s, size_t width) {
  return s.size() >= width ? s : std::string(width - s.size(), ' ') + s;
}

// Adds the points of one level's error quantiles to the curve: the tree after `level_merges` merges,
// holding `merges` of them.
void addCurvePoints(std::vector<MergeErrorPoint>& curve, size_t level, uint64_t level_merges, uint64_t merges,
                    const std::vector<double>& quantiles, uint64_t points0) {
  if (quantiles.size() != 9 || merges == 0 || points0 == 0) return;
  for (size_t k = 0; k < 9; ++k) {
    // computeErrorQuantiles takes the (i+1)-th smallest error, i = round(q * (merges - 1)).
    const uint64_t i = std::min<uint64_t>(
        merges - 1, static_cast<uint64_t>(std::llround(kMergeErrorQuantiles[k] * double(merges - 1))));
    MergeErrorPoint p;
    p.merges = level_merges + i + 1;
    p.ratio = double(p.merges) / double(points0);
    p.error = quantiles[k];
    p.level = level;
    p.quantile = kMergeErrorQuantiles[k];
    curve.push_back(p);
  }
}
}  // namespace

StatusOr<std::optional<MergeTreeReport>> mergeTreeReport(GtnReader& r) {
  GTN_ASSIGN_OR_RETURN(std::optional<MergeTree> whole, wholeMergeTree(r, 0));
  if (!whole) return std::optional<MergeTreeReport>();
  const uint64_t points0 = r.level(0).header.points;
  const MergeTree& tree = *whole;
  MergeTreeReport rep;
  rep.stats = computeMergeTreeStats(tree);
  rep.field = tree.field;
  rep.w_density = tree.w_density;
  rep.w_geometry = tree.w_geometry;
  rep.error_quantiles = tree.error_quantiles;
  addCurvePoints(rep.error_curve, 0, 0, tree.merges, tree.error_quantiles, points0);
  for (size_t i = 0; i < r.levels(); ++i) {
    const GtnLevelInfo& l = r.level(i);
    MergeTreeLevelRow row;
    row.level = i;
    row.ratio = l.ratio;
    row.points = l.header.points;
    row.tets = l.header.tets;
    row.merges = l.header.merges;
    row.bytes = l.bytes;
    row.has_merge_tree = l.has_merge_tree;
    rep.levels.push_back(row);
    if (i == 0 || !l.has_merge_tree || l.header.merges >= tree.merges) continue;
    // A level's tree holds the merges after its own: only its header (the quantiles) is needed.
    auto level_payload = r.mergeTreePayload(i);
    if (!level_payload.isOk()) return level_payload.status();
    if (!level_payload.value().has_value()) continue;
    GTN_ASSIGN_OR_RETURN(MergeTree head, decodeMergeTree(*level_payload.value(), l.header.points,
                                                         r.file().path + ", level " + std::to_string(i), nullptr, 0));
    addCurvePoints(rep.error_curve, i, l.header.merges, tree.merges - l.header.merges, head.error_quantiles, points0);
  }
  std::stable_sort(rep.error_curve.begin(), rep.error_curve.end(),
                   [](const MergeErrorPoint& a, const MergeErrorPoint& b) { return a.merges < b.merges; });
  double largest = 0;
  for (MergeErrorPoint& p : rep.error_curve) p.largest_error = largest = std::max(largest, p.error);
  for (MergeTreeLevelRow& row : rep.levels) {
    if (row.merges == 0) continue;
    for (const MergeErrorPoint& p : rep.error_curve)
      if (p.merges <= row.merges) row.largest_error = p.largest_error;
  }
  return std::optional<MergeTreeReport>(std::move(rep));
}

nlohmann::json mergeTreeReportJson(const MergeTreeReport& rep) {
  nlohmann::json q = nlohmann::json::object();
  for (size_t i = 0; i < rep.error_quantiles.size() && i < 9; ++i) q[kQuantileNames[i]] = rep.error_quantiles[i];
  nlohmann::json levels = nlohmann::json::array();
  for (const MergeTreeLevelRow& l : rep.levels)
    levels.push_back({{"level", l.level},
                      {"ratio", l.ratio},
                      {"points", l.points},
                      {"tets", l.tets},
                      {"merges", l.merges},
                      {"bytes", l.bytes},
                      {"merge_tree", l.has_merge_tree},
                      {"largest_error", l.largest_error ? nlohmann::json(*l.largest_error) : nlohmann::json(nullptr)}});
  nlohmann::json curve = nlohmann::json::array();
  for (const MergeErrorPoint& p : rep.error_curve)
    curve.push_back({{"ratio", p.ratio},
                     {"merges", p.merges},
                     {"error", p.error},
                     {"largest_error", p.largest_error},
                     {"level", p.level},
                     {"quantile", p.quantile}});
  const MergeTreeStats& s = rep.stats;
  return nlohmann::json{{"merges", s.merges},
                        {"roots", s.roots},
                        {"boundary_merges", s.boundary_merges},
                        {"tets_removed", s.tets_removed},
                        {"depth", {{"max", s.depth_max}, {"mean", s.depth_mean}}},
                        {"fanout", {{"max", s.fanout_max}, {"mean", s.fanout_mean}}},
                        {"error_quantiles", q},
                        {"field", rep.field},
                        {"w_density", rep.w_density},
                        {"w_geometry", rep.w_geometry},
                        {"levels", levels},
                        {"error_curve", curve}};
}

std::string mergeTreeReportText(const MergeTreeReport& rep, const std::string& in) {
  const MergeTreeStats& s = rep.stats;
  std::string t;
  auto line = [&](const std::string& label, const std::string& value) { t += in + padRight(label, 20) + value + "\n"; };
  line("ranking", (rep.field.empty() ? std::string("volume only (no density field)") : "density field " + rep.field) +
                      ", w_density " + general(rep.w_density) + ", w_geometry " + general(rep.w_geometry));
  line("merges", number(s.merges) + " of " + number(s.points) + " vertices (boundary " + number(s.boundary_merges) +
                     "), " + number(s.tets_removed) + " tetrahedra removed");
  line("roots", number(s.roots));
  line("depth", "max " + number(s.depth_max) + ", mean " + format("%.3f", s.depth_mean));
  line("fan-out", "max " + number(s.fanout_max) + ", mean " + format("%.3f", s.fanout_mean));
  if (rep.error_quantiles.size() == 9) {
    std::string names, values;
    for (size_t i = 0; i < 9; ++i) {
      names += padLeft(kQuantileNames[i], 12);
      values += padLeft(format("%.4g", rep.error_quantiles[i]), 12);
    }
    line("error quantiles", names.substr(2));
    line("", values.substr(2));
  } else {
    line("error quantiles", "none stored");
  }
  t += in + "level      ratio      points  tetrahedra       bytes      merges  largest error\n";
  for (const MergeTreeLevelRow& l : rep.levels) {
    t += in + padRight(number(l.level), 5) + padLeft(format("%.6f", l.ratio), 11) + padLeft(number(l.points), 12) +
         padLeft(number(l.tets), 12) + padLeft(number(l.bytes), 12) + padLeft(number(l.merges), 12) +
         padLeft(l.largest_error ? format("%.4g", *l.largest_error) : std::string("-"), 15) +
         (l.has_merge_tree ? "" : "  (no merge tree)") + "\n";
  }
  return t;
}

nlohmann::json meshInfoJson(const MeshStats& s, const ImportReport& r, const TetMesh& mesh) {
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
                      {"min", f.has_range ? nlohmann::json(f.min) : nlohmann::json(nullptr)},
                      {"max", f.has_range ? nlohmann::json(f.max) : nlohmann::json(nullptr)},
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

LevelZeroBytes levelZeroBytes(const GtnReader& r) {
  LevelZeroBytes b;
  b.total = r.file().bytes;
  for (size_t i = 1; i < r.levels(); ++i) b.total -= r.level(i).bytes;
  const GtnLevelInfo& l0 = r.level(0);
  for (const GtnChunkInfo& c : l0.chunks) {
    if (c.tag == kTagSeam || c.tag == kTagGrid) {
      b.connectivity += c.bytes;
    } else if (l0.pieceStoredRaw(c)) {
      // Its streams by kind, its framing with the connectivity (boundary and peeling).
      const std::vector<uint64_t>& sizes = l0.piece_streams[c.piece];
      for (size_t k = 0; k < sizes.size(); ++k) (k == 2 ? b.geometry : k > 2 ? b.fields : b.connectivity) += sizes[k];
      b.connectivity += kChunkFixedHeaderSize + kChunkChecksumSize;
    } else if (c.tag == kTagPiece) {
      b.connectivity += c.bytes;  // stored compressed: its streams' shares are not known (as in sections())
    } else if (c.tag == kTagMergeTree) {
      b.merge_tree += c.bytes;
    }
  }
  return b;
}

StatusOr<nlohmann::json> gtnInfoJson(GtnReader& r, const TetMesh& mesh, const MeshStats& stats,
                                     const DecodeStats& decode_stats, bool merge_tree) {
  const GtnFileInfo& f = r.file();
  const LevelZeroBytes bytes = levelZeroBytes(r);
  const double tets = static_cast<double>(r.level(0).header.tets);
  auto bpt = [&](uint64_t bytes) -> nlohmann::json {
    if (tets == 0) return nullptr;
    return 8.0 * static_cast<double>(bytes) / tets;
  };
  nlohmann::json j = meshInfoJson(stats, ImportReport{}, mesh);
  j.erase("import");
  j["format"] = "gtn";
  j["format_version"] = std::to_string(f.major) + "." + std::to_string(f.minor);
  j["bytes"] = f.bytes;
  j["provenance"] = {{"tool_version", f.header.tool_version}, {"command_line", f.header.command_line}};
  j["has_directory"] = f.has_directory;
  j["draft"] = f.header.draft;
  j["piece_tets"] = f.header.piece_tets;
  nlohmann::json sections = nlohmann::json::array();
  for (const GtnSection& s : r.sections()) sections.push_back({{"name", s.name}, {"bytes", s.bytes}});
  j["sections"] = sections;
  j["bits_per_tet"] = {{"connectivity", bpt(bytes.connectivity)},
                       {"geometry", bpt(bytes.geometry)},
                       {"fields", bpt(bytes.fields)},
                       {"merge_tree", bpt(bytes.merge_tree)},
                       {"total", bpt(bytes.total)}};
  j["peak_live_vertices"] = decode_stats.peak_live_vertices;
  nlohmann::json levels = nlohmann::json::array();
  for (size_t i = 0; i < r.levels(); ++i) {
    const GtnLevelInfo& l = r.level(i);
    nlohmann::json chunks = nlohmann::json::array();
    for (const GtnChunkInfo& c : l.chunks) {
      nlohmann::json chunk = {{"type", c.tag.str()},
                              {"section", c.section},
                              {"bytes", c.bytes},
                              {"raw_bytes", c.raw_bytes},
                              {"zstd", c.zstd}};
      if (c.piece != kNoIndex) chunk["piece"] = c.piece;
      chunks.push_back(std::move(chunk));
    }
    nlohmann::json pieces = nlohmann::json::array();
    for (size_t p = 0; p < l.pieces.size(); ++p) {
      const PieceInfo& pi = l.pieces[p];
      pieces.push_back({{"piece", p},
                        {"kind", pi.kind},
                        {"points", pi.points},
                        {"own_points", pi.own_points},
                        {"tets", pi.tets},
                        {"boundary_triangles", pi.boundary_triangles},
                        {"bbox",
                         {{"min", {pi.bbox_min[0], pi.bbox_min[1], pi.bbox_min[2]}},
                          {"max", {pi.bbox_max[0], pi.bbox_max[1], pi.bbox_max[2]}}}},
                        {"bytes", l.pieceBytes(p)}});
    }
    levels.push_back({{"level", i},
                      {"points", l.header.points},
                      {"tets", l.header.tets},
                      {"boundary_triangles", l.header.boundary_triangles},
                      {"merges", l.header.merges},
                      {"ratio", l.ratio},
                      {"merge_tree", l.has_merge_tree},
                      {"names_next_level", l.base != 0},
                      {"bytes", l.bytes},
                      {"piece_count", l.pieces.size()},
                      {"pieces", pieces},
                      {"chunks", chunks}});
  }
  j["levels"] = levels;
  if (merge_tree) {
    GTN_ASSIGN_OR_RETURN(std::optional<MergeTreeReport> mt, mergeTreeReport(r));
    j["merge_tree"] = mt ? mergeTreeReportJson(*mt) : nlohmann::json(nullptr);
  }
  return j;
}

StatusOr<nlohmann::json> infoJson(const std::vector<std::string>& inputs, const ImportOptions& options, bool merge_tree,
                                  std::vector<std::string>* warnings) {
  if (inputs.empty()) return usageError("info: no input");
  bool gtn = false;
  for (const std::string& in : inputs)
    // Standard input cannot be sniffed without consuming it: only a .gtn file is read from a pipe.
    if (in == "-" || detectInputFormat(in) == InputFormat::kGtn) gtn = true;
  if (gtn) {
    if (inputs.size() != 1) return usageError("gtn info reads one .gtn file at a time");
    GTN_ASSIGN_OR_RETURN(std::unique_ptr<GtnReader> reader, GtnReader::open(inputs[0]));
    TetMeshBuilder builder;
    DecodeStats decode_stats;
    GTN_RETURN_IF_ERROR(reader->decodeLevel(0, builder, &decode_stats));
    GTN_ASSIGN_OR_RETURN(nlohmann::json j, gtnInfoJson(*reader, builder.mesh(), computeMeshStats(builder.mesh()),
                                                       decode_stats, merge_tree));
    j["input"] = inputs;
    return j;
  }
  GTN_ASSIGN_OR_RETURN(ImportResult imported, importMesh(inputs, options));
  if (warnings) {
    for (const std::string& w : imported.report.warnings) warnings->push_back(w);
    if (merge_tree)
      warnings->push_back(inputs[0] + ": --merge-tree describes the merge tree of a .gtn file; a mesh has none");
  }
  nlohmann::json j = meshInfoJson(computeMeshStats(imported.mesh), imported.report, imported.mesh);
  j["input"] = inputs;
  return j;
}

}  // namespace gtn
