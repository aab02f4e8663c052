// What `gtn export` and `gtn decode` share: opening a .gtn to read one view of it (a stored level, or
// the mesh simplified to a ratio or by a number of merges), and decoding that view into a sink.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "format/decode_fields.h"
#include "format/gtn_reader.h"
#include "mesh/mesh_stream.h"
#include "simplify/levels.h"

namespace gtn::cli {

// Opens `input` for random access through its directory, every chunk read checksummed, damage
// elsewhere in the file held in `damage` (said once the command knows its outcome). A mesh file given
// instead gets a usage error that says `gtn <command>` reads .gtn files and `convert_hint` (what to
// run instead).
StatusOr<std::unique_ptr<GtnReader>> openForView(const std::string& input, const std::string& command,
                                                 const std::string& convert_hint, HeldWarnings& damage);

struct ViewRequest {
  size_t level = 0;
  // --box: only the pieces of the stored level whose bounding boxes meet [box_lo, box_hi] are decoded
  // (codec/pieces.h piecesInBox), and the view is those pieces' tetrahedra.
  bool has_box = false;
  double box_lo[3] = {0, 0, 0}, box_hi[3] = {0, 0, 0};
  double ratio = -1;                // < 0: not given
  int64_t merges = -1;              // < 0: not given; takes precedence over ratio
  std::vector<std::string> fields;  // empty: every field
};

// Parses --box's "XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX" into `v` (a usage error naming the option otherwise).
Status parseBox(const std::string& text, ViewRequest* v);

// Decodes the view `v` of `r` (opened from `input`) into `sink`: the level is checked, the fields
// chosen (`*fields` says which were decoded), then the level decoded or, with a ratio or merges, the
// mesh simplified from the nearest level (`plan` receives the level and the extra merges; may be null).
Status decodeView(GtnReader& r, const std::string& input, const ViewRequest& v, MeshSink& sink, DecodeFields* fields,
                  SimplifyPlan* plan);

}  // namespace gtn::cli
