// Choosing which fields a decode reads (`gtn export --fields`, `gatun.read(fields=...)`).
#pragma once

#include <string>
#include <vector>

#include "codec/level_codec.h"
#include "mesh/mesh_stream.h"
#include "mesh/tet_mesh.h"

namespace gtn {

// The point and cell fields named in `names` (a name may be both), as a decode selection for a level
// with header `h`. A name the level lacks is a usage error "<input>: <option>: no field named 'x'
// (fields: a, b)", `option` naming what the caller calls the list.
StatusOr<DecodeFields> selectDecodeFields(const LevelHeader& h, const std::vector<std::string>& names,
                                          const std::string& input, const std::string& option);

// Drops from `mesh` the fields `keep` leaves out (their values were not decoded).
void dropUndecodedFields(TetMesh& mesh, const DecodeFields& keep);

}  // namespace gtn
