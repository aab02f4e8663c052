#include "render/render_input.h"

#include <cmath>

#include "convert/import.h"
#include "simplify/levels.h"
#include "simplify/stream_simplifier.h"

namespace gtn {

RenderInput::~RenderInput() = default;

StatusOr<std::unique_ptr<RenderInput>> RenderInput::open(const std::vector<std::string>& inputs) {
  if (inputs.empty()) return usageError("no input to render");
  std::unique_ptr<RenderInput> in(new RenderInput());
  const std::string& path = inputs[0];
  in->path_ = path;
  if (inputs.size() == 1 && detectInputFormat(path) == InputFormat::kGtn) {
    GtnOpenOptions options;
    options.verify = false;  // chunks are still checksummed as they are read
    GTN_ASSIGN_OR_RETURN(in->reader_, GtnReader::open(path, options));
    if (in->reader_->levels() == 0) return invalidData(path + ": the file holds no level");
    return in;
  }
  GTN_ASSIGN_OR_RETURN(ImportResult imported, importMesh(inputs, ImportOptions()));
  GTN_ASSIGN_OR_RETURN(EncodedLevel encoded, encodeLevel(imported.mesh, EncodeOptions()));
  in->encoded_ = std::make_unique<EncodedLevel>(std::move(encoded));
  return in;
}

size_t RenderInput::levels() const { return reader_ ? reader_->levels() : 1; }

const LevelHeader& RenderInput::levelHeader(size_t i) const {
  return reader_ ? reader_->level(i).header : encoded_->header;
}

bool RenderInput::hasMergeTree(size_t i) const { return reader_ && reader_->level(i).has_merge_tree; }

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
    target = static_cast<int64_t>(std::llround(choice.ratio * static_cast<double>(levelZeroPoints())));
  }
  fill(0);
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

Status RenderInput::stream(const ResolvedLevel& level, MeshSink& sink) {
  if (!reader_) {
    return decodeLevel(encoded_->header, payloadOf(*encoded_), sink, nullptr, path_);
  }
  if (level.extra_merges == 0) return reader_->decodeLevel(level.level, sink);
  GTN_ASSIGN_OR_RETURN(auto payload, reader_->mergeTreePayload(level.level));
  if (!payload) return usageError(path_ + ": level " + std::to_string(level.level) + " has no merge tree");
  GTN_ASSIGN_OR_RETURN(MergeTree tree,
                       decodeMergeTree(*payload, level.points, path_ + ": level " + std::to_string(level.level)));
  StreamSimplifier simplifier(tree, level.extra_merges, sink);
  return reader_->decodeLevel(level.level, simplifier);
}

}  // namespace gtn
