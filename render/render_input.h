// What the renderer reads: a .gtn file (any stored level, simplified further on the fly by its merge
// tree), or any mesh the importers read (encoded in memory with the level codec, so that it still
// arrives as a real decode stream). Choosing the level for --ratio / --merges follows the paper's
// section 5: start from the most simplified stored level that is not coarser than the target, then
// apply the remaining merges on the fly (simplify/stream_simplifier.h).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "codec/level_codec.h"
#include "format/gtn_reader.h"
#include "mesh/mesh_stream.h"
#include "mesh/progress.h"
#include "render/ray_cast.h"

namespace gtn {

// At most one of level / ratio / merges is set (>= 0).
struct LevelChoice {
  int level = -1;       // a stored level as is
  double ratio = -1;    // vertices merged away / vertices of level 0, in [0, 1]
  int64_t merges = -1;  // merges of the level-0 merge tree
};

struct ResolvedLevel {
  size_t level = 0;               // stored level decoded
  uint64_t stored_merges = 0;     // merges already applied in that level
  uint64_t extra_merges = 0;      // merges applied on the fly
  uint64_t points = 0, tets = 0;  // of the stored level (what is decoded)
  // Asked for by number (--merges): more than the merge tree holds is an error. Merges from a ratio
  // stop where the tree ends (stream lowers extra_merges to what it applied).
  bool exact_merges = false;
  uint64_t total_merges() const { return stored_merges + extra_merges; }
};

class RenderInput {
 public:
  // One .gtn file, or the inputs of one mesh as `gtn convert` takes them (PLOT3D grid + Q, ...).
  static StatusOr<std::unique_ptr<RenderInput>> open(const std::vector<std::string>& inputs);
  ~RenderInput();

  // Optional: stream() reports "decode level I" with the share of its tetrahedra (mesh/progress.h).
  void setProgress(ProgressFn fn) { progress_ = std::move(fn); }

  // What open() found and the caller should say: damaged chunks of a .gtn file that may not be needed,
  // or what the importer of a mesh file left out or changed ("<file>: <warning>").
  const std::vector<std::string>& warnings() const { return warnings_; }

  size_t levels() const;
  const LevelHeader& levelHeader(size_t i) const;
  bool hasMergeTree(size_t i) const;
  // The merges level i's merge tree holds (what can be applied on the fly on top of it); 0 without.
  StatusOr<uint64_t> mergeTreeMerges(size_t i);
  uint64_t levelZeroPoints() const { return levelHeader(0).points; }
  // Merges of level 0's unused points (simplify/levels.h, levelZeroUnreferencedMerges): ratios count
  // the other points. 0 for a mesh file rendered directly.
  StatusOr<uint64_t> unreferencedMerges();

  // Fails with kUsage for a level that does not exist, a ratio outside [0, 1], or simplification of
  // an input without a merge tree.
  StatusOr<ResolvedLevel> resolve(const LevelChoice& choice) const;
  // Decodes the chosen level into `sink`, through the on-the-fly simplifier when extra merges apply.
  // With `only`, the values of that scalar's field alone are decoded (the renderers read no other):
  // the other fields' values reach the sink unspecified. Fails with kUsage when it selects nothing.
  Status stream(ResolvedLevel& level, MeshSink& sink, const FieldSelector* only = nullptr);

  // Fixes what must not change between levels of one file: the camera frames level 0's bounding box,
  // and, unless the caller gave a range, the transfer function spans the selected scalar over level
  // 0's boundary vertices (read by decoding level 0 up to the end of its boundary; for level 0 itself
  // the renderer computes the same range). Simplification moves and merges boundary vertices, so
  // without this a simplified view would shift its colours and its framing against the full one.
  Status fixView(const ResolvedLevel& level, RenderOptions* options);
  // Fails (naming `input`) when `field` selects none of the level's point fields, and says so when it
  // names a cell field: checked before anything is decoded.
  Status checkPointField(const ResolvedLevel& level, const FieldSelector& field, const std::string& input) const;

 private:
  RenderInput() = default;
  std::string path_;
  std::vector<std::string> warnings_;
  ProgressFn progress_;
  std::unique_ptr<GtnReader> reader_;      // .gtn input
  std::unique_ptr<EncodedLevel> encoded_;  // any other input, encoded in memory
};

}  // namespace gtn
