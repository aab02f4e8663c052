// What `gtn info --json` reports, as JSON objects that the CLI prints and the Python package returns
// as dicts, and the statistics of a file's merge trees (`gtn info --merge-tree`, `--plot`).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "codec/level_codec.h"
#include "convert/import.h"
#include "format/gtn_reader.h"
#include "mesh/mesh_stats.h"
#include "simplify/apply.h"

namespace gtn {

// One stored level as the merge-tree table shows it.
struct MergeTreeLevelRow {
  size_t level = 0;
  double ratio = 0;  // vertices merged away / vertices of level 0
  uint64_t points = 0, tets = 0, merges = 0, bytes = 0;
  bool has_merge_tree = false;
  // The largest merge error the stored error quantiles place at or before the level's merge count
  // (see MergeTreeReport::error_curve); none for level 0 (no merge applied) or without quantiles.
  std::optional<double> largest_error;
};

// A point of the error curve: `error` is the error quantile `quantile` of the merges a level's tree
// still holds, placed at `merges` = that level's merge count plus the quantile's position among its
// merges, i.e. at ratio merges / points of level 0. The ranking takes the cheapest merge first, so
// errors rise with rank (nearly: a merge changes its neighbours' errors) and the curve is the error
// against the simplification ratio. A level's smallest quantiles fall below the curve before it (the
// merges it still holds include some the ranking put late), so `largest_error`, the largest error of
// the curve up to this point, is the curve to read.
struct MergeErrorPoint {
  double ratio = 0;
  uint64_t merges = 0;
  double error = 0;
  double largest_error = 0;
  size_t level = 0;
  double quantile = 0;
};

struct MergeTreeReport {
  MergeTreeStats stats;  // of level 0's whole tree
  std::string field;     // density field of the ranking, "" = volume only
  double w_density = 0, w_geometry = 0;
  std::vector<double> error_quantiles;  // level 0's: 0 or 9 values at kMergeErrorQuantiles
  std::vector<MergeTreeLevelRow> levels;
  std::vector<MergeErrorPoint> error_curve;  // ascending merges
};

// The statistics of `reader`'s merge trees: level 0's tree decoded whole, the other levels' headers
// (their error quantiles). nullopt when level 0 stores no merge tree.
StatusOr<std::optional<MergeTreeReport>> mergeTreeReport(GtnReader& reader);

// The report as `gtn info --json --merge-tree` prints it under "merge_tree".
nlohmann::json mergeTreeReportJson(const MergeTreeReport& report);

// The report as a table for people, each line starting with `indent`.
std::string mergeTreeReportText(const MergeTreeReport& report, const std::string& indent);

// `gtn info --json` for mesh files: statistics, metadata and what the import changed.
nlohmann::json meshInfoJson(const MeshStats& stats, const ImportReport& report, const TetMesh& mesh);

// Level 0's share of a .gtn file in bytes, by kind of chunk; `total` is level 0's chunks plus
// everything that is not another level's (header, directory, trailer).
struct LevelZeroBytes {
  uint64_t connectivity = 0, geometry = 0, fields = 0, merge_tree = 0, total = 0;
};
LevelZeroBytes levelZeroBytes(const GtnReader& reader);

// `gtn info --json` for a .gtn file whose level 0 `reader` decoded into `level0` (with
// `decode_stats`; `stats` = computeMeshStats(level0)): container, provenance, sections, bits per
// tetrahedron, levels and level 0's statistics; with `merge_tree`, "merge_tree" too (null when the
// file stores none). No "input" key.
StatusOr<nlohmann::json> gtnInfoJson(GtnReader& reader, const TetMesh& level0, const MeshStats& stats,
                                     const DecodeStats& decode_stats, bool merge_tree);

// `gtn info --json [--merge-tree] INPUTS...` whole: one .gtn file (fully verified) or mesh files as
// `gtn convert` reads them. `warnings` (optional) receives the importer's warnings.
StatusOr<nlohmann::json> infoJson(const std::vector<std::string>& inputs, const ImportOptions& options, bool merge_tree,
                                  std::vector<std::string>* warnings = nullptr);

}  // namespace gtn
