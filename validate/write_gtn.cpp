#include "validate/write_gtn.h"

#include <tbb/task_group.h>

#include "simplify/levels.h"
#include "validate/mesh_checks.h"

namespace gtn {

namespace {
Status writeLevels(const std::string& path, const TetMesh& mesh, const GtnConvertOptions& o, const GtnWriteOptions& wo,
                   const std::string& source, std::vector<std::string>* warnings) {
  if (o.levels == 0 && !o.merge_tree) {
    GtnLevelInput level0;
    level0.mesh = &mesh;
    return writeGtnFile(path, {level0}, wo);
  }
  reportProgress(wo.progress, "rank merges", 0.0);
  GTN_RETURN_IF_ERROR(checkRankingOptions(mesh, o.ranking));
  // Level 0 is encoded while the merges are ranked: on another thread where TBB has one, after the
  // ranking where it has not. A level 0 that fails to encode is left to the writer, which fails on it
  // where it always has (after the level checks).
  std::shared_ptr<EncodedLevel> level0;
  tbb::task_group encoding;
  encoding.run([&] {
    auto e = encodeLevel(mesh, EncodeOptions{});
    if (e.isOk()) level0 = std::make_shared<EncodedLevel>(std::move(e).value());
  });
  RankingStats ranked;
  StatusOr<MergeTree> ranking = rankMerges(mesh, o.ranking, &ranked, wo.progress);
  encoding.wait();
  if (!ranking.isOk()) return ranking.status();
  MergeTree tree = std::move(ranking).value();
  if (const std::string note = defaultFieldNote(ranked); !note.empty() && warnings)
    warnings->push_back(source + ": " + note);
  reportProgress(wo.progress, "build levels");
  LevelOptions lo;
  lo.levels = o.levels;
  lo.merge_tree = o.merge_tree;
  GTN_ASSIGN_OR_RETURN(MipLevels levels, buildMipLevels(mesh, tree, lo));
  // Part of the verification: every level the simplifier made is a valid mesh.
  if (wo.verify) GTN_RETURN_IF_ERROR(checkLevelStructure(levels.levelMeshes(mesh), path));
  // Levels stop where the merge tree does (a small or flat mesh has few merges): say so rather than
  // write fewer levels than asked for without a word.
  if (o.levels > 0 && levels.merges.size() - 1 < static_cast<size_t>(o.levels) && warnings)
    warnings->push_back(source + ": --levels " + std::to_string(o.levels) + ": the merge tree has " +
                        std::to_string(tree.merges) + " merge(s) of " + std::to_string(mesh.numPoints()) +
                        " points, enough for " + std::to_string(levels.merges.size() - 1) + " level(s) beyond level 0");
  GtnWriteOptions bounded = wo;
  if (o.levels < 0) bounded.level_storage_limit = o.level_storage;
  std::vector<GtnLevelInput> inputs = levels.inputs(mesh);
  inputs[0].encoded = std::move(level0);
  return writeGtnFile(path, inputs, bounded);
}
}  // namespace

Status writeGtnWithLevels(const std::string& path, const TetMesh& mesh, const GtnConvertOptions& options,
                          const GtnWriteOptions& write_options, const std::string& source,
                          std::vector<std::string>* warnings) {
  Status st = writeLevels(path, mesh, options, write_options, source, warnings);
  // The encoder's refusals are about the mesh: name it.
  if (!st.isOk() && st.message().rfind("encodeLevel: ", 0) == 0)
    st = Status(st.code(), source + ": cannot be encoded: " + st.message().substr(13));
  return st;
}

}  // namespace gtn
