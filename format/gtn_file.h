// CONTRACT for the .gtn container (owned by format/; spec in spec/gtn-format.md). Writing and reading
// whole files; the reader decodes front to back and streams each level to a MeshSink.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "codec/level_codec.h"
#include "mesh/mesh_stream.h"
#include "mesh/tet_mesh.h"

namespace gtn {

// One level to write. For level 0 `merges` is 0; for mip level i it is the number of merge-tree merges
// already applied to obtain `mesh`. `merge_tree` (optional) produces the level's merge-tree chunk
// payload given encodeLevel's vertex_order for this level (so the tree is stored in decoding order).
struct GtnLevelInput {
  const TetMesh* mesh = nullptr;
  uint64_t merges = 0;
  double ratio = 0.0;  // vertices merged away / all vertices of level 0
  std::function<StatusOr<std::vector<uint8_t>>(const std::vector<uint32_t>& vertex_order)> merge_tree;
};

struct GtnWriteOptions {
  std::string tool_version;  // provenance
  std::string command_line;  // provenance
  bool zstd = true;          // zstd-compress chunks where it helps
  bool directory = true;     // write the directory and trailer for random access
};

Status writeGtnFile(const std::string& path, const std::vector<GtnLevelInput>& levels,
                    const GtnWriteOptions& options);
