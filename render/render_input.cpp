#include "render/render_input.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <unordered_map>

#include "convert/import.h"
#include "render/time_budget.h"
#include "simplify/levels.h"
#include "simplify/stream_simplifier.h"

namespace gtn {

RenderInput::~RenderInput() = default;

StatusOr<std::unique_ptr<RenderInput>> RenderInput::open(const std::vector<std::string>& inputs) {
  if (inputs.empty()) return usageError("no input to render");
  std::unique_ptr<RenderInput> in(new RenderInput());
  const std::string& path = inputs[0];
  in->path_ = path;
  if (inputs.size() == 1 && (path == "-" || detectInputFormat(path) == InputFormat::kGtn)) {  // "-": a .gtn stream
    GtnOpenOptions options;
    options.verify = false;  // chunks are still checksummed as they are read
    RenderInput* self = in.get();
    GTN_ASSIGN_OR_RETURN(in->reader_,
                         openGtnChecked(path, options, [self](const std::string& w) { self->warnings_.push_back(w); }));
    if (in->reader_->levels() == 0) return invalidData(path + ": the file holds no level");
    return in;
  }
  GTN_ASSIGN_OR_RETURN(ImportResult imported, importMesh(inputs, ImportOptions()));
  for (const std::string& w : imported.report.warnings) in->warnings_.push_back(path + ": " + w);  // what it left out
  GTN_ASSIGN_OR_RETURN(EncodedLevel encoded, encodeLevel(imported.mesh, EncodeOptions()));
  in->encoded_ = std::make_unique<EncodedLevel>(std::move(encoded));
  return in;
}

size_t RenderInput::levels() const { return reader_ ? reader_->levels() : 1; }

const LevelHeader& RenderInput::levelHeader(size_t i) const {
  return reader_ ? reader_->level(i).header : encoded_->header;
}

StatusOr<uint64_t> RenderInput::unreferencedMerges() {
  if (!reader_) return uint64_t{0};
  return levelZeroUnreferencedMerges(*reader_);
}

bool RenderInput::hasMergeTree(size_t i) const { return reader_ && reader_->level(i).has_merge_tree; }

StatusOr<uint64_t> RenderInput::mergeTreeMerges(size_t i) {
  if (!hasMergeTree(i)) return uint64_t{0};
  GTN_ASSIGN_OR_RETURN(auto payload, reader_->mergeTreePayload(i));
  if (!payload) return uint64_t{0};
  GTN_ASSIGN_OR_RETURN(MergeTreeHeader header,
                       readMergeTreeHeader(*payload, levelHeader(i).points, path_ + ": level " + std::to_string(i)));
  return header.merges;
}

StatusOr<ResolvedLevel> RenderInput::resolve(const LevelChoice& choice) const {
  ResolvedLevel r;
  auto fill = [&](size_t level) {
    r.level = level;
    r.stored_merges = levelHeader(level).merges;
    r.points = levelHeader(level).points;
    r.tets = levelHeader(level).tets;
  };
  if (choice.level >= 0) {
    if (static_cast<size_t>(choice.level) >= levels())
      return usageError(path_ + ": no level " + std::to_string(choice.level) + " (the input has " +
                        std::to_string(levels()) + ")");
    fill(static_cast<size_t>(choice.level));
    return r;
  }
  int64_t target = choice.merges;
  if (choice.ratio >= 0) {
    if (!(choice.ratio <= 1)) return usageError("--ratio must lie in [0, 1]");
    if (reader_) {  // counted over the points tetrahedra use (simplify/levels.h)
      GTN_ASSIGN_OR_RETURN(const uint64_t merges, mergesForRatio(*reader_, choice.ratio));
      target = static_cast<int64_t>(merges);
    } else {
      target = static_cast<int64_t>(std::llround(choice.ratio * static_cast<double>(levelZeroPoints())));
    }
  }
  fill(0);
  r.exact_merges = choice.ratio < 0;
  if (target <= 0) return r;
  std::vector<uint64_t> stored;
  for (size_t i = 0; i < levels(); ++i) stored.push_back(levelHeader(i).merges);
  const size_t level = chooseLevel(stored, static_cast<uint64_t>(target));
  fill(level);
  r.extra_merges = static_cast<uint64_t>(target) - r.stored_merges;
  if (r.extra_merges > 0 && !hasMergeTree(level))
    return usageError(path_ + ": simplifying on the fly needs a merge tree, and level " + std::to_string(level) +
                      " has none" + (reader_ ? "" : " (convert the input to .gtn first)"));
  return r;
}

Status RenderInput::stream(ResolvedLevel& level, MeshSink& out, const FieldSelector* only) {
  ProgressMeshSink shown(out, progress_, "decode and render level " + std::to_string(level.level));
  MeshSink& sink = progress_ ? static_cast<MeshSink&>(shown) : out;
  DecodeFields fields;
  if (only) {
    const LevelHeader& h = levelHeader(level.level);
    GTN_ASSIGN_OR_RETURN(ScalarReader reader, ScalarReader::create(h.point_fields, *only));
    fields = reader.decodeFields(h.point_fields.size(), h.cell_fields.size());
  }
  if (!reader_) {
    return decodeLevel(encoded_->header, payloadOf(*encoded_), sink, nullptr, path_, &fields);
  }
  if (level.extra_merges == 0) return reader_->decodeLevel(level.level, sink, nullptr, &fields);
  if (!reader_->level(level.level).has_merge_tree)
    return usageError(path_ + ": level " + std::to_string(level.level) + " has no merge tree");
  GTN_ASSIGN_OR_RETURN(LevelTree stored, levelMergeTree(*reader_, level.level, level.extra_merges, &fields));
  const MergeTree& tree = stored.tree;
  if (tree.merges < level.extra_merges) {
    if (level.exact_merges)
      return usageError(path_ + ", level " + std::to_string(level.level) + ": " + std::to_string(level.total_merges()) +
                        " merges requested, the merge tree has " + std::to_string(level.stored_merges + tree.merges));
    level.extra_merges = tree.merges;
  }
  StreamSimplifier simplifier(tree, level.extra_merges, sink);
  return emitLevel(*reader_, stored, simplifier, &fields);
}

}  // namespace gtn

namespace gtn {

namespace {
// Reads a level's boundary and stops the decode at its end: the scalar range over the boundary
// vertices, as the renderers compute it (boundaryRange).
class BoundaryRangeSink : public MeshSink {
 public:
  explicit BoundaryRangeSink(const FieldSelector& field) : field_(field) {}
  Status beginLevel(const LevelHeader& header) override {
    GTN_ASSIGN_OR_RETURN(reader_, ScalarReader::create(header.point_fields, field_));
    return Status::ok();
  }
  Status vertex(uint32_t id, const double xyz[3], const uint8_t* values) override {
    scalars_.emplace(id, reader_.read(values));
    (void)xyz;
    return Status::ok();
  }
  Status boundaryTriangle(const uint32_t v[3]) override {
    std::array<uint32_t, 3> t;
    for (int i = 0; i < 3; ++i) {
      auto [it, inserted] = local_.emplace(v[i], static_cast<uint32_t>(surface_.scalars.size()));
      if (inserted) {
        auto s = scalars_.find(v[i]);
        if (s == scalars_.end()) return invalidData("boundary triangle refers to a vertex not yet emitted");
        surface_.scalars.push_back(s->second);
      }
      t[i] = it->second;
    }
    surface_.triangles.push_back(t);
    return Status::ok();
  }
  Status endBoundary() override {
    stopped_ = true;
    return Status(StatusCode::kUnsupported, "boundary read");  // stops the decode; not an error
  }
  Status tet(const uint32_t*, const uint8_t*) override { return Status::ok(); }
  Status retireVertex(uint32_t) override { return Status::ok(); }
  Status endLevel() override { return Status::ok(); }

  bool stopped() const { return stopped_; }
  std::pair<double, double> range() const { return boundaryRange(surface_); }

 private:
  FieldSelector field_;
  ScalarReader reader_;
  std::unordered_map<uint32_t, double> scalars_;
  std::unordered_map<uint32_t, uint32_t> local_;
  BoundarySurface surface_;
  bool stopped_ = false;
};
}  // namespace

Status RenderInput::fixView(const ResolvedLevel& level, RenderOptions* options) {
  const LevelHeader& h0 = levelHeader(0);
  // The crossing arithmetic multiplies three coordinates (or their differences): beyond about 1e100
  // it overflows, below about 1e-100 it underflows, and the image came out blank without a word.
  double largest = 0, extent = 0;
  for (int i = 0; i < 3; ++i) {
    largest = std::max({largest, std::fabs(h0.bbox_min[i]), std::fabs(h0.bbox_max[i])});
    extent = std::max(extent, h0.bbox_max[i] - h0.bbox_min[i]);
  }
  if (largest > 1e100 || (extent > 0 && extent < 1e-100)) {
    char why[200];
    std::snprintf(why, sizeof why,
                  ": coordinates up to %g across %g cannot be rendered (the ray crossings need sizes between "
                  "1e-100 and 1e100); scale the mesh",
                  largest, extent);
    return unsupported(path_ + why);
  }
  bool box_ok = false;
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(h0.bbox_min[i]) || !std::isfinite(h0.bbox_max[i]) || h0.bbox_min[i] > h0.bbox_max[i]) {
      box_ok = false;
      break;
    }
    if (h0.bbox_min[i] < h0.bbox_max[i]) box_ok = true;
  }
  if (box_ok && !options->has_scene_box) {
    options->has_scene_box = true;
    for (int i = 0; i < 3; ++i) options->scene_min[i] = h0.bbox_min[i], options->scene_max[i] = h0.bbox_max[i];
  }
  if (options->transfer.has_range || !reader_ || (level.level == 0 && level.extra_merges == 0)) return Status::ok();
  if (const auto cached = options->use_cache ? cachedBoundaryRange(path_, options->field) : std::nullopt) {
    options->transfer.has_range = true;
    options->transfer.lo = cached->first;
    options->transfer.hi = cached->second;
    return Status::ok();
  }
  BoundaryRangeSink sink(options->field);
  GTN_ASSIGN_OR_RETURN(ScalarReader reader, ScalarReader::create(h0.point_fields, options->field));
  const DecodeFields fields = reader.decodeFields(h0.point_fields.size(), h0.cell_fields.size());
  const Status st = reader_->decodeLevel(0, sink, nullptr, &fields);
  if (!sink.stopped()) {
    GTN_RETURN_IF_ERROR(st);
    return Status::ok();  // a level without boundary: the renderer's own default applies
  }
  const auto [lo, hi] = sink.range();
  if (options->use_cache) storeBoundaryRange(path_, options->field, {lo, hi});
  options->transfer.has_range = true;
  options->transfer.lo = lo;
  options->transfer.hi = hi;
  return Status::ok();
}

Status RenderInput::checkPointField(const ResolvedLevel& level, const FieldSelector& field,
                                    const std::string& input) const {
  const LevelHeader& header = levelHeader(level.level);
  auto reader = ScalarReader::create(header.point_fields, field);
  if (reader.isOk()) return Status::ok();
  std::string why = reader.status().message();
  for (const FieldDesc& c : header.cell_fields)
    if (c.name == field.name) why += "; '" + c.name + "' is a cell field, and render shows point fields";
  return Status(reader.status().code(), input + ": " + why);
}

}  // namespace gtn
