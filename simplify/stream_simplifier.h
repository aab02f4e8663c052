// On-the-fly simplification of the mesh stream (paper section 4.2): a MeshSink filter between the
// decoder and any consumer. Given the level's merge tree (in the stream's vertex numbering, i.e.
// decoding order) and a threshold n, it computes every vertex's ancestor once, then forwards
//  - the vertices that survive (ancestor = itself), renumbered in their emission order;
//  - each tetrahedron and boundary triangle with its vertices replaced by their ancestors, dropped
//    when two of them coincide, held back only until all its ancestors have been emitted;
//  - the retirement of a surviving vertex once every vertex merged into it has been retired
//    upstream and no held-back element refers to it.
// The output is exactly applyMerges(level, tree, n) (simplify/apply.h) up to vertex and tetrahedron
// order. The output header's counts are exact (the tree records what each merge removes); a stream
// that disagrees with them (a corrupt tree) fails with kInvalidData. The bounding box is the input's.
// Memory: 5 bytes per input vertex, 12 per surviving vertex, plus the held-back elements.
#pragma once

#include <cstdint>
#include <vector>

#include "codec/merge_tree_coder.h"
#include "mesh/mesh_stream.h"

namespace gtn {

class StreamSimplifier : public MeshSink {
 public:
  // `tree` must outlive the filter; n is clamped to tree.merges.
  StreamSimplifier(const MergeTree& tree, uint64_t n, MeshSink& out);

  Status beginLevel(const LevelHeader& header) override;
  Status vertex(uint32_t id, const double xyz[3], const uint8_t* values) override;
  Status boundaryTriangle(const uint32_t v[3]) override;
  Status endBoundary() override;
  Status tet(const uint32_t v[4], const uint8_t* cell_values) override;
  Status retireVertex(uint32_t id) override;
  Status endLevel() override;
  // A level given whole (a structured piece) to a sink that takes it whole is simplified whole, on
  // every thread: the surviving vertices in input order, the tetrahedra and boundary triangles that
  // keep four and three distinct vertices in input order.
  bool takesWholeLevel() const override { return out_.takesWholeLevel(); }
  Status wholeLevel(const LevelHeader& header, TetMesh&& mesh,
                    std::vector<std::array<uint32_t, 3>>&& boundary) override;

  uint64_t droppedTets() const { return dropped_tets_; }
  uint64_t peakHeld() const { return peak_held_; }

 private:
  // Output ids: surviving vertices are numbered in their input order, so the ancestor of a vertex
  // has been emitted exactly when its output id is below emitted_, and a held element waits only for
  // its largest output id: the others are emitted before it.
  struct Held {
    uint32_t o[4];  // output ids of the ancestors; o[3] unused for triangles
    uint32_t next;  // the next element waiting for the same vertex, or kNoIndex
    bool triangle;
  };
  // beginLevel's work but for passing the header on: the ancestors' output ids and the counts.
  Status prepare(const LevelHeader& header);
  Status emitHeld(uint32_t slot);
  Status release(uint32_t o);  // drops one reference, retires when none is left
  Status hold(const uint32_t* o, int count, bool triangle, const uint8_t* cell_values);

  const MergeTree& tree_;
  uint64_t n_;
  MeshSink& out_;
  LevelHeader in_header_, out_header_;
  size_t cell_bytes_ = 0;
  std::vector<uint32_t> out_of_;   // per input vertex: output id of its ancestor
  std::vector<uint8_t> survives_;  // per input vertex: 1 if it is its own ancestor
  std::vector<uint32_t> refs_;     // per output vertex: unretired cluster members + held elements
  uint32_t received_ = 0, emitted_ = 0;
  uint64_t out_tets_ = 0, out_triangles_ = 0, dropped_tets_ = 0;
  std::vector<Held> held_;
  std::vector<uint8_t> held_values_;
  std::vector<uint32_t> free_slots_;
  // Held elements waiting for an output vertex, as intrusive first-in first-out lists through
  // Held::next: wait_head_[o] is the first, wait_tail_[o] the last.
  std::vector<uint32_t> wait_head_, wait_tail_;
  uint64_t held_count_ = 0, peak_held_ = 0;
  bool in_boundary_ = true;
};

}  // namespace gtn
