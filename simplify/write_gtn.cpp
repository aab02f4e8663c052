#include "simplify/write_gtn.h"

#include "simplify/levels.h"

namespace gtn {

namespace {
Status writeLevels(const std::string& path, const TetMesh& mesh, const GtnConvertOptions& o,
                   const GtnWriteOptions& wo, const std::string& source, std::vector<std::string>* warnings) {
  if (o.levels == 0 && !o.merge_tree) {
    GtnLevelInput level0;
    level0.mesh = &mesh;
    return writeGtnFile(path, {level0}, wo);
  }
  GTN_ASSIGN_OR_RETURN(MergeTree tree, rankMerges(mesh, o.ranking, nullptr));
  LevelOptions lo;
  lo.levels = o.levels;
  lo.merge_tree = o.merge_tree;
  GTN_ASSIGN_OR_RETURN(MipLevels levels, buildMipLevels(mesh, tree, lo));
  // Levels stop where the merge tree does (a small or flat mesh has few merges): say so rather than
  // write fewer levels than asked for without a word.
  if (o.levels > 0 && levels.merges.size() - 1 < static_cast<size_t>(o.levels) && warnings)
    warnings->push_back(source + ": --levels " + std::to_string(o.levels) + ": the merge tree has " +
                        std::to_string(tree.merges) + " merge(s) of " + std::to_string(mesh.numPoints()) +
                        " points, enough for " + std::to_string(levels.merges.size() - 1) +
                        " level(s) beyond level 0");
  GtnWriteOptions bounded = wo;
  if (o.levels < 0) bounded.level_storage_limit = o.level_storage;
  return writeGtnFile(path, levels.inputs(mesh), bounded);
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
