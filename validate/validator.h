// The reference validator behind `gtn validate`: checks a .gtn file in layers (container, decoding,
// mesh, merge tree, levels, and optionally against the source it was made from) and gathers every
// finding in a ValidationReport. Issue codes are listed in validate/issues.h.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "convert/import.h"
#include "mesh/faces.h"
#include "mesh/mesh_stream.h"
#include "mesh/tet_mesh.h"
#include "validate/merge_checks.h"
#include "validate/report.h"

namespace gtn {

struct ValidateOptions {
  bool quick = false;                // container and checksums only
  size_t max_issues = 100;           // messages kept in the report (counts stay exact)
  std::vector<std::string> against;  // source files: level 0 must equal the imported source
  ImportOptions import_options;      // how to import `against` (e.g. --split 5 for PLOT3D)
  // Take the split and --weld for `against` from level 0's metadata (import.split, import.weld, as
  // `gtn convert` records them) instead of import_options (the CLI: when --split, --weld are not given).
  bool split_from_file = false;
  bool weld_from_file = false;
};

// One decoded level as the validator examines it.
struct DecodedLevel {
  uint32_t level = 0;
  LevelHeader header;
  TetMesh mesh;
  std::vector<Triangle> boundary;  // the boundary surface as stored (decoded) in the file
  double ratio = -1.0;             // declared ratio, negative when none
};

// What the file holds once decoded (the input of the mesh, merge-tree and levels layers).
struct DecodedFile {
  std::vector<DecodedLevel> levels;  // level 0 first
  std::optional<MergeForest> forest;
  bool forest_undecodable = false;  // level 0 has a merge tree that did not decode (already reported)
  std::string command_line;         // the file header's provenance (hints in messages)
};

// Runs the mesh, merge-tree, levels and --against layers on decoded content.
void validateDecoded(const DecodedFile& file, const ValidateOptions& options, ValidationReport& report);

// Compares level 0 with a source mesh up to renumbering: counts, field descriptions, then bit-exact
// positions and values of every point and tetrahedron (SOURCE_* issues).
// `hint` (optional) is added to a SOURCE_COUNT_MISMATCH message.
void compareWithSource(const TetMesh& level0, const TetMesh& source, ValidationReport& report,
                       const std::string& hint = "");

// Validates the bytes of a .gtn file; every problem becomes an issue (this never fails).
ValidationReport validateGtnBytes(std::span<const uint8_t> bytes, const std::string& name,
                                  const ValidateOptions& options);

// Reads and validates a file. A non-OK status only when the file cannot be read (exit code 3).
StatusOr<ValidationReport> validateGtnFile(const std::string& path, const ValidateOptions& options);

// Validates the mesh that mesh files describe (anything `gtn convert` reads: one mesh file, PLOT3D grid
// and Q files, a TetGen basename, a Medit mesh and its solutions), imported with
// options.import_options: what the importer changed (import layer), then the mesh checks of a level
// under the scope "/mesh". A file the importer rejects is an IMPORT_FAILED error; a non-OK status only
// when a file cannot be opened or read (exit code 3).
StatusOr<ValidationReport> validateMeshFiles(const std::vector<std::string>& inputs, const ValidateOptions& options);

}  // namespace gtn
