// Importers: every supported input format into a TetMesh, orientation normalised, with a report of
// what was changed on the way in. The dispatcher picks the format from each input's extension and
// content.
#pragma once

#include <string>
#include <vector>

#include "mesh/tet_mesh.h"

namespace gtn {

struct ImportOptions {
  int split = 6;      // hexahedra into 5 (alternating parity) or 6 (consistent diagonals) tetrahedra
  bool weld = false;  // merge bit-identical points, drop tetrahedra that collapse (weldPoints)
  // Medit meshes: solution files (.sol, .solb) whose values become fields (readMeditSolutions).
  std::vector<std::string> medit_solutions;
  // Exodus II: the time step (1-based) whose variables become fields; 0 reads the last one.
  int exodus_time_step = 0;
};

// Metadata that importMesh adds to a mesh imported with options other than the defaults (a .gtn input
// keeps its own): the split ("5") and --weld ("yes"). `gtn validate --against` reads them.
inline constexpr const char* kMetadataSplit = "import.split";
inline constexpr const char* kMetadataWeld = "import.weld";

enum class InputFormat { kUnknown, kPlot3d, kTetgen, kVtkLegacy, kVtu, kMedit, kMeshb, kOff, kGtn, kGmsh, kExodus };
const char* inputFormatName(InputFormat f);

// Format of one input path from its extension and first bytes.
InputFormat detectInputFormat(const std::string& path);

// Imports the mesh that `inputs` describe together: one mesh file, a TetGen basename or any of its
// files, PLOT3D grid [+ Q] [+ function] files or a .p3d meta-file, or a Medit mesh and its solution
// files (.sol, .solb).
StatusOr<ImportResult> importMesh(const std::vector<std::string>& inputs, const ImportOptions& options);

// The importers (each in its own file under convert/).
StatusOr<ImportResult> importPlot3d(const std::vector<std::string>& inputs, const ImportOptions& options);
StatusOr<ImportResult> importTetgen(const std::string& path, const ImportOptions& options);
StatusOr<ImportResult> importVtkLegacy(const std::string& path, const ImportOptions& options);
StatusOr<ImportResult> importVtu(const std::string& path, const ImportOptions& options);
StatusOr<ImportResult> importMedit(const std::string& path, const ImportOptions& options);
StatusOr<ImportResult> importMeshb(const std::string& path, const ImportOptions& options);
StatusOr<ImportResult> importOff(const std::string& path, const ImportOptions& options);
StatusOr<ImportResult> importGmsh(const std::string& path, const ImportOptions& options);
StatusOr<ImportResult> importExodus(const std::string& path, const ImportOptions& options);

// Normalises orientation after an importer built `result.mesh`: flips negative tetrahedra, counts
// flips and zero-volume cells into the report.
void finishImport(ImportResult& result);

// Keeps the points p with keep[p] (coordinates and point field values moved down, in order) and
// returns each point's new index (kNoIndex for a point dropped); renumbering the tetrahedra is the
// caller's.
std::vector<uint32_t> keepPoints(TetMesh& mesh, const std::vector<uint8_t>& keep);
// --weld: merges points whose three coordinates are bit-identical into the first of them (its point
// field values are kept), drops the tetrahedra that lose a vertex that way (with their cell field
// values) and compacts points and point fields. Closes the seams between PLOT3D blocks and between
// the pieces of VTK files; importMesh applies it when options.weld is set.
void weldPoints(TetMesh& mesh, ImportReport& report);
// Each point's welded identity: the first point (smallest index) whose coordinates are bit-identical
// to its own.
std::vector<uint32_t> weldIdentities(const TetMesh& mesh);

}  // namespace gtn
