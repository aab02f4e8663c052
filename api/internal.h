// Conversions between the public API's types (include/gatun/) and the layers' own, for api/*.cpp only.
#pragma once

#include <string>
#include <vector>

#include "gatun/convert.h"
#include "gatun/mesh.h"
#include "gatun/result.h"
#include "convert/import.h"
#include "mesh/status.h"
#include "mesh/tet_mesh.h"

namespace gatun::internal {

// A failed Status as an Error (the same code and message); an ok one as an ok Error.
Error toError(const gtn::Status& status);

// The library's mesh from the API's (fields and metadata copied) and back (moved).
gtn::TetMesh toTetMesh(const Mesh& mesh);
Mesh fromTetMesh(gtn::TetMesh&& mesh);

gtn::ImportOptions toImportOptions(const ImportOptions& options);

// What an importer changed, as `gtn convert` says it: one line per kind of change, each naming `input`.
void appendImportWarnings(const std::string& input, const gtn::ImportReport& report,
                          std::vector<std::string>* warnings);

}  // namespace gatun::internal
