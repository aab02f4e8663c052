// Conversions between the public API's types (include/gatun/) and the layers' own, for api/*.cpp only.
// In namespace gtn, so that libgatun does not export them (api/gatun.map).
#pragma once

#include <string>
#include <vector>

#include "convert/import.h"
#include "gatun/convert.h"
#include "gatun/mesh.h"
#include "gatun/result.h"
#include "mesh/status.h"
#include "mesh/tet_mesh.h"

namespace gtn::api {

// A failed Status as an Error (the same code and message); an ok one as an ok Error.
gatun::Error toError(const Status& status);

// The library's mesh from the API's (fields and metadata copied) and back (moved).
TetMesh toTetMesh(const gatun::Mesh& mesh);
gatun::Mesh fromTetMesh(TetMesh&& mesh);

ImportOptions toImportOptions(const gatun::ImportOptions& options);

// What an importer changed, as `gtn convert` says it: one line per kind of change, each naming `input`.
void appendImportWarnings(const std::string& input, const ImportReport& report, std::vector<std::string>* warnings);

}  // namespace gtn::api
