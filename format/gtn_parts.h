// Writing one .gtn from a mesh held in parts (the ranks of a distributed dataset, e.g. ParaView's
// pvbatch under MPI): each part codes its own pieces of level 0 (codec/pieces.h, "A level held in
// parts"), part 0 settles the seams between them and writes the file. What passes between the parts
// is small: the keys, pieces and values of each part's exposed points (its boundary), the seam plan,
// and the coded pieces. The file holds level 0 alone (no mip level, no merge tree: both need the whole
// mesh in one place).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "codec/pieces.h"
#include "format/gtn_file.h"
#include "mesh/tet_mesh.h"

namespace gtn {

// How the parts talk (MPI in the ParaView plugin; threads in the tests). Every part calls each
// operation in the same order.
class PartExchange {
 public:
  virtual ~PartExchange() = default;
  virtual int part() const = 0;   // this part's index, 0 .. parts() - 1
  virtual int parts() const = 0;  // at least 1
  // On part 0 `all` receives every part's `mine` in part order; elsewhere it is left empty.
  virtual Status gather(const std::vector<uint8_t>& mine, std::vector<std::vector<uint8_t>>* all) = 0;
  // Part 0's `bytes` reach every part.
  virtual Status broadcast(std::vector<uint8_t>* bytes) = 0;
};

// Who coded what (filled on every part).
struct PartsWriteReport {
  std::vector<uint32_t> pieces_per_part;  // in part order: the file's pieces are the parts' in turn
  uint64_t points = 0, tets = 0;          // of the level written
  uint64_t exposed_points = 0;            // all parts' exposed points (what went to part 0)
  uint64_t seam_points = 0;
};

// Writes `path` (on part 0, atomically) from every part's `part` mesh (positively oriented
// tetrahedra) and its points' keys (`keys`: one per point of the part, PointKey; `coordinate_keys`:
// they are coordinates, not global ids). Each part cuts its
// mesh into pieces of at most options.piece_tets tetrahedra and codes them; with options.verify each
// part decodes its pieces back from the level as written and compares them with its mesh before part
// 0 commits the file. Every part returns the same status; messages name `path` and, for a part's own
// failure, the part. The parts' copies of a shared point must agree bit for bit (coordinates and
// point values), their fields must be the same; parts with no tetrahedra add nothing.
// options.command_line is recorded with " (N parts: P0 P1 ... pieces)" appended. A part that could not
// make its mesh passes its failure as `local_failure` (its mesh and keys are then not used): every part fails
// with it.
Status writeGtnFromParts(const std::string& path, const TetMesh& part, const std::vector<PointKey>& keys,
                         bool coordinate_keys, PartExchange& exchange, const GtnWriteOptions& options,
                         PartsWriteReport* report = nullptr, const Status& local_failure = Status::ok());

}  // namespace gtn
