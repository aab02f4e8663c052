// Progress of long work, reported through a callback: library code says which stage it is in and how
// far it has got, and prints nothing; a front end (the CLI's line on a terminal) decides what to show.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "mesh/mesh_stream.h"

namespace gtn {

// `stage` names the work ("encode level 1 (3 levels)"); `fraction` is how much of it is done, in
// [0, 1], or negative when that is not known. Calls may come from several threads, so a callback must
// be thread-safe; callers report at most every few thousand items, so it may take a lock.
using ProgressFn = std::function<void(const std::string& stage, double fraction)>;

// Calls `fn` when it is set, so that reporting code need not test for it.
inline void reportProgress(const ProgressFn& fn, const std::string& stage, double fraction = -1.0) {
  if (fn) fn(stage, fraction);
}

// Passes a level's events on to `inner` and reports `stage` with the share of the level's tetrahedra
// streamed so far (every 65536 tetrahedra).
class ProgressMeshSink : public MeshSink {
 public:
  ProgressMeshSink(MeshSink& inner, ProgressFn fn, std::string stage)
      : inner_(inner), fn_(std::move(fn)), stage_(std::move(stage)) {}
  Status beginLevel(const LevelHeader& header) override {
    total_ = header.tets;
    done_ = 0;
    reportProgress(fn_, stage_, 0.0);
    return inner_.beginLevel(header);
  }
  Status vertex(uint32_t id, const double xyz[3], const uint8_t* values) override {
    return inner_.vertex(id, xyz, values);
  }
  Status boundaryTriangle(const uint32_t v[3]) override { return inner_.boundaryTriangle(v); }
  Status endBoundary() override { return inner_.endBoundary(); }
  Status tet(const uint32_t v[4], const uint8_t* cell_values) override {
    if ((++done_ & 0xFFFF) == 0 && total_ > 0)
      reportProgress(fn_, stage_, static_cast<double>(done_) / static_cast<double>(total_));
    return inner_.tet(v, cell_values);
  }
  Status retireVertex(uint32_t id) override { return inner_.retireVertex(id); }
  Status endLevel() override {
    reportProgress(fn_, stage_, 1.0);
    return inner_.endLevel();
  }

 private:
  MeshSink& inner_;
  ProgressFn fn_;
  std::string stage_;
  uint64_t total_ = 0, done_ = 0;
};

}  // namespace gtn
