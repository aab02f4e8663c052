#include "render/default_field.h"

#include <algorithm>
#include <cmath>

#include "mesh/mesh_stats.h"
#include "render/ray_cast.h"

namespace gtn {

namespace {
// Whether each point field's first component (what the renderer reads of it by default) takes two
// finite values; stops the decode once the first field has (it is then the one).
class VariesSink : public MeshSink {
 public:
  Status beginLevel(const LevelHeader& header) override {
    for (const FieldDesc& d : header.point_fields) {
      FieldSelector sel;
      sel.name = d.name;
      GTN_ASSIGN_OR_RETURN(ScalarReader r, ScalarReader::create(header.point_fields, sel));
      readers_.push_back(std::move(r));
    }
    first_.assign(readers_.size(), 0.0);
    seen_.assign(readers_.size(), false);
    varies.assign(readers_.size(), false);
    return Status::ok();
  }
  Status vertex(uint32_t, const double*, const uint8_t* values) override {
    for (size_t i = 0; i < readers_.size(); ++i) {
      if (varies[i]) continue;
      const double v = readers_[i].read(values);
      if (std::isfinite(v)) {
        if (!seen_[i]) {
          seen_[i] = true;
          first_[i] = v;
        } else if (v != first_[i]) {
          varies[i] = true;
        }
      }
    }
    if (!varies[0]) return Status::ok();
    stopped = true;
    return Status(StatusCode::kUnsupported, "the first field varies");  // stops the decode; not an error
  }
  Status boundaryTriangle(const uint32_t*) override { return Status::ok(); }
  Status endBoundary() override { return Status::ok(); }
  Status tet(const uint32_t*, const uint8_t*) override { return Status::ok(); }
  Status retireVertex(uint32_t) override { return Status::ok(); }
  Status endLevel() override { return Status::ok(); }

  std::vector<bool> varies;
  bool stopped = false;

 private:
  std::vector<ScalarReader> readers_;
  std::vector<double> first_;
  std::vector<bool> seen_;
};
}  // namespace

StatusOr<RenderFieldChoice> chooseRenderField(RenderInput& input) {
  RenderFieldChoice choice;
  const size_t coarsest = input.levels() - 1;
  const LevelHeader& h = input.levelHeader(coarsest);
  if (h.point_fields.size() < 2) return choice;
  ResolvedLevel level;
  level.level = coarsest;
  level.stored_merges = h.merges;
  level.points = h.points;
  level.tets = h.tets;
  VariesSink sink;
  const Status st = input.stream(level, sink);
  if (!sink.stopped) GTN_RETURN_IF_ERROR(st);
  const size_t chosen = defaultPointField(sink.varies);
  for (size_t i = 0; i < std::min(chosen, sink.varies.size()); ++i) choice.constant.push_back(h.point_fields[i].name);
  if (chosen != SIZE_MAX) choice.name = h.point_fields[chosen].name;
  return choice;
}

}  // namespace gtn
