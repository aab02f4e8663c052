#include "simplify/levels.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>

#include <tbb/task_group.h>

#include "codec/merge_tree_coder.h"
#include "format/gtn_reader.h"
#include "mesh/wait_on_exit.h"
#include "simplify/apply.h"
#include "simplify/stream_simplifier.h"

namespace gtn {

uint64_t levelMerges(int level, uint64_t points, uint64_t merges) {
  if (level <= 0) return 0;
  const double n = std::round((1.0 - std::ldexp(1.0, -level)) * static_cast<double>(points));
  return std::min<uint64_t>(static_cast<uint64_t>(n), merges);
}

MipLevelBuilder::MipLevelBuilder(const TetMesh& source, const MergeTree& tree, bool keep_trees)
    : source_(&source), tree_(&tree), keep_trees_(keep_trees) {
  meshes_.emplace_back();
  // Level 0's tree is the caller's: not copied.
  finest_tree_ = std::shared_ptr<const MergeTree>(std::shared_ptr<const MergeTree>(), &tree);
  trees_.push_back(keep_trees ? finest_tree_ : nullptr);
}

StatusOr<MipLevelBuilder> MipLevelBuilder::create(const TetMesh& source, const MergeTree& tree,
                                                  const LevelOptions& options, const RuleGridTets* source_tets) {
  if (tree.points() != source.numPoints()) return invalidData("mip levels: merge tree does not match the mesh");
  GTN_RETURN_IF_ERROR(tree.check("mip levels: merge tree"));
  MipLevelBuilder out(source, tree, options.merge_tree);
  out.source_tets_ = source_tets;
  out.source_tet_count_ = source_tets ? source_tets->size() : source.numTets();
  out.merges_.push_back(0);
  out.ratios_.push_back(0.0);
  // Counted over the vertices tetrahedra use: the merges of the others come first and count for nothing.
  const uint64_t free = leadingFreeMerges(tree);
  const uint64_t points = source.numPoints() - free;
  const int max_levels = options.levels < 0 ? 62 : options.levels;
  for (int i = 1; i <= max_levels; ++i) {
    const uint64_t n = free + levelMerges(i, points, tree.merges - free);
    if (n <= out.merges_.back()) break;  // the tree is exhausted
    if (options.levels < 0 && points - (n - free) < options.min_points) break;
    if (options.levels < 0 && out.source_tet_count_ - tree.tetsRemovedUpTo(n) < options.min_tets) break;
    out.merges_.push_back(n);
    out.ratios_.push_back(points ? static_cast<double>(n - free) / static_cast<double>(points) : 0.0);
  }
  return out;
}

StatusOr<const TetMesh*> MipLevelBuilder::level(size_t i) {
  if (i >= count())
    return usageError("mip level " + std::to_string(i) + " asked for, of " + std::to_string(count()) + " levels");
  if (i > 0 && i < skip_to_) return usageError("mip level " + std::to_string(i) + " asked for, after it was skipped");
  if (meshes_.size() == 1 && skip_to_ > 1 && i > 0) {
    // Level skip_to_ straight from the source: the levels between are placeholders.
    std::vector<uint32_t> index;
    GTN_ASSIGN_OR_RETURN(TetMesh mesh, applyMerges(*source_, *tree_, merges_[skip_to_], &index, source_tets_));
    finest_tree_ = std::make_shared<const MergeTree>(remainingTree(*tree_, merges_[skip_to_], index));
    for (size_t k = 1; k < skip_to_; ++k) {
      trees_.push_back(nullptr);
      next_index_.emplace_back();
      meshes_.push_back(nullptr);
    }
    next_index_.emplace_back();  // level skip_to_ - 1 is not made: nothing maps into level skip_to_
    trees_.push_back(keep_trees_ ? finest_tree_ : nullptr);
    meshes_.push_back(std::make_unique<TetMesh>(std::move(mesh)));
  }
  // Level i is made from level i - 1 and its tree (the rest of the merges, in its numbering): the same
  // mesh and tree as from the source (compaction keeps the vertex and tetrahedron order), in time that
  // shrinks with the levels instead of a pass over the source for each.
  while (meshes_.size() <= i) {
    const size_t next = meshes_.size();
    const TetMesh& finer = next == 1 ? *source_ : *meshes_.back();
    const uint64_t step = merges_[next] - merges_[next - 1];
    std::vector<uint32_t> index;
    GTN_ASSIGN_OR_RETURN(TetMesh mesh,
                         applyMerges(finer, *finest_tree_, step, &index, next == 1 ? source_tets_ : nullptr));
    finest_tree_ = std::make_shared<const MergeTree>(remainingTree(*finest_tree_, step, index));
    trees_.push_back(keep_trees_ ? finest_tree_ : nullptr);
    next_index_.push_back(std::move(index));
    meshes_.push_back(std::make_unique<TetMesh>(std::move(mesh)));
  }
  return i == 0 ? source_ : meshes_[i].get();
}

uint64_t MipLevelBuilder::tetsOf(size_t i) const {
  return i < count() ? source_tet_count_ - tree_->tetsRemovedUpTo(merges_[i]) : 0;
}

StatusOr<MipLevels> buildMipLevels(const TetMesh& source, const MergeTree& tree, const LevelOptions& options) {
  GTN_ASSIGN_OR_RETURN(MipLevelBuilder builder, MipLevelBuilder::create(source, tree, options));
  MipLevels out;
  out.merges = builder.merges();
  out.ratios = builder.ratios();
  out.meshes.emplace_back();
  out.trees.push_back(options.merge_tree ? std::make_shared<const MergeTree>(tree) : nullptr);
  GTN_RETURN_IF_ERROR(builder.level(builder.count() - 1).status());
  for (size_t i = 1; i < builder.count(); ++i) {
    out.meshes.push_back(std::move(*builder.meshes_[i]));
    out.trees.push_back(builder.tree(i));
  }
  out.next_index = std::move(builder.next_index_);
  return out;
}

std::vector<GtnLevelInput> MipLevels::inputs(const TetMesh& source, const MergeTreeForm& level0_form) const {
  std::vector<GtnLevelInput> result;
  for (size_t i = 0; i < merges.size(); ++i) {
    GtnLevelInput in;
    in.mesh = i == 0 ? &source : &meshes[i];
    in.merges = merges[i];
    in.ratio = ratios[i];
    if (trees[i]) {
      std::shared_ptr<const MergeTree> t = trees[i];
      const TetMesh* mesh = in.mesh;
      const MergeTreeForm form = i == 0 ? level0_form : MergeTreeForm{};
      in.merge_tree = [t, mesh, form](const std::vector<uint32_t>& vertex_order) {
        return encodeMergeTree(*t, vertex_order, mesh, form);
      };
      in.merge_tree_prefix = [t, mesh, form](const std::vector<uint32_t>& vertex_order, uint64_t n,
                                             const std::vector<uint32_t>& next_index) {
        MergeTreeForm chained = form;
        chained.next_index = &next_index;
        return encodeMergeTree(n < t->merges ? prefixTree(*t, n) : *t, vertex_order, mesh, chained);
      };
    }
    if (i < next_index.size()) {
      const std::vector<uint32_t>* next = &next_index[i];
      in.next_index = [next]() -> StatusOr<std::vector<uint32_t>> { return *next; };
    }
    result.push_back(std::move(in));
  }
  return result;
}

std::vector<const TetMesh*> MipLevels::levelMeshes(const TetMesh& source) const {
  std::vector<const TetMesh*> result = {&source};
  for (size_t i = 1; i < meshes.size(); ++i) result.push_back(&meshes[i]);
  return result;
}

size_t chooseLevel(const std::vector<uint64_t>& level_merges, uint64_t target_merges) {
  size_t best = 0;
  for (size_t i = 0; i < level_merges.size(); ++i) {
    if (level_merges[i] <= target_merges) best = i;
  }
  return best;
}

}  // namespace gtn

namespace gtn {

StatusOr<SimplifyPlan> planSimplification(const GtnReader& reader, uint64_t target_merges) {
  if (reader.levels() == 0) return invalidData(reader.file().path + ": the file has no levels");
  std::vector<uint64_t> merges;
  for (size_t i = 0; i < reader.levels(); ++i) merges.push_back(reader.level(i).header.merges);
  // Levels are stored coarser and coarser; choose among those not beyond the target.
  SimplifyPlan plan;
  plan.level = 0;
  for (size_t i = 0; i < merges.size(); ++i) {
    if (merges[i] <= target_merges && merges[i] >= merges[plan.level]) plan.level = i;
  }
  plan.extra_merges = target_merges - merges[plan.level];
  return plan;
}

StatusOr<std::optional<MergeTree>> wholeMergeTree(GtnReader& reader, size_t i,
                                                  const std::vector<std::vector<uint32_t>>* base_ids,
                                                  const std::vector<const TetMesh*>* meshes) {
  if (i >= reader.levels()) return usageError(reader.file().path + ": level " + std::to_string(i) + " does not exist");
  size_t last = i;  // the end of the chain: the first level that stores all its vertices
  while (last + 1 < reader.levels() && reader.level(last).base != 0) ++last;
  // Level k's mesh, decoded here unless the caller has it (then `ids` gets the names it gives the
  // next level's vertices too).
  std::unique_ptr<TetMeshBuilder> own_mesh;
  std::vector<uint32_t> decoded;
  auto meshOf = [&](size_t k, std::vector<uint32_t>* ids) -> StatusOr<const TetMesh*> {
    if (meshes && k < meshes->size() && (*meshes)[k] && !ids) return (*meshes)[k];
    own_mesh = std::make_unique<TetMeshBuilder>();
    GTN_RETURN_IF_ERROR(reader.decodeLevel(k, *own_mesh, nullptr, nullptr, ids));
    return &own_mesh->mesh();
  };
  auto treeOf = [&](size_t k, uint64_t max_merges, const TetMesh* mesh,
                    const std::vector<uint32_t>* ids) -> StatusOr<std::optional<MergeTree>> {
    GTN_ASSIGN_OR_RETURN(auto payload, reader.mergeTreePayload(k));
    if (!payload) return std::optional<MergeTree>();
    const std::string what = reader.file().path + ", level " + std::to_string(k);
    if (!mesh) {
      GTN_ASSIGN_OR_RETURN(MergeTreeHeader h, readMergeTreeHeader(*payload, reader.level(k).header.points, what));
      if (h.needs_mesh) {
        GTN_ASSIGN_OR_RETURN(mesh, meshOf(k, nullptr));
      }
    }
    GTN_ASSIGN_OR_RETURN(MergeTree t,
                         decodeMergeTree(*payload, reader.level(k).header.points, what, mesh, max_merges, ids));
    return std::optional<MergeTree>(std::move(t));
  };
  GTN_ASSIGN_OR_RETURN(std::optional<MergeTree> whole, treeOf(last, UINT64_MAX, nullptr, nullptr));
  if (!whole) return whole;
  for (size_t k = last; k-- > i;) {
    const std::string what = reader.file().path + ", level " + std::to_string(k);
    const uint64_t band =
        reader.level(k + 1).header.merges - std::min(reader.level(k + 1).header.merges, reader.level(k).header.merges);
    const std::vector<uint32_t>* ids =
        base_ids && k < base_ids->size() && !(*base_ids)[k].empty() ? &(*base_ids)[k] : nullptr;
    const TetMesh* mesh = nullptr;
    if (!ids) {
      decoded.clear();
      GTN_ASSIGN_OR_RETURN(mesh, meshOf(k, &decoded));
      ids = &decoded;
    }
    GTN_ASSIGN_OR_RETURN(std::optional<MergeTree> own, treeOf(k, band, mesh, ids));
    if (!own) return own;
    if (own->merges != band)
      return invalidData(what + ": its merge tree holds " + std::to_string(own->merges) + " merges, " +
                         std::to_string(band) + " are needed down to level " + std::to_string(k + 1));
    const size_t n = own->points(), next_n = whole->points();
    if (ids->size() != n) return invalidData(what + ": the ids of the next level's vertices do not match the level");
    std::vector<uint32_t> here(next_n, kNoIndex);  // next level's id -> this level's id
    for (uint32_t v = 0; v < n; ++v) {
      const uint32_t u = (*ids)[v];
      if (u == kNoIndex) continue;
      if (u >= next_n || here[u] != kNoIndex)
        return invalidData(what + ": vertex " + std::to_string(v) + " names a vertex of level " +
                           std::to_string(k + 1) + " out of range or named twice");
      here[u] = v;
    }
    MergeTree t = std::move(*own);
    for (uint32_t v = 0; v < n; ++v) {
      const uint32_t u = (*ids)[v];
      const bool merged_here = t.rank[v] != 0;
      if (merged_here == (u != kNoIndex))
        return invalidData(what + ": vertex " + std::to_string(v) +
                           (merged_here
                                ? " merges before level " + std::to_string(k + 1) + " but is one of its vertices"
                                : " is neither a vertex of level " + std::to_string(k + 1) + " nor merged before it"));
      if (merged_here || whole->rank[u] == 0) continue;
      if (here[whole->parent[u]] == kNoIndex)
        return invalidData(what + ": a merge of level " + std::to_string(k + 1) + " has a parent this level lacks");
      t.parent[v] = here[whole->parent[u]];
      t.rank[v] = static_cast<uint32_t>(band + whole->rank[u]);
      t.removed[v] = whole->removed[u];
      t.boundary[v] = whole->boundary[u];
      if (!t.error.empty() && u < whole->error.size()) t.error[v] = whole->error[u];
    }
    t.merges = band + whole->merges;
    t.batches.insert(t.batches.end(), whole->batches.begin(), whole->batches.end());
    t.checked = false;
    GTN_RETURN_IF_ERROR(t.check(what + ": merge tree with the next levels'"));
    whole = std::move(t);
  }
  return whole;
}

StatusOr<uint64_t> levelZeroUnreferencedMerges(GtnReader& reader) {
  if (reader.levels() == 0 || !reader.level(0).has_merge_tree) return uint64_t{0};
  GTN_ASSIGN_OR_RETURN(auto payload, reader.mergeTreePayload(0));
  if (!payload) return uint64_t{0};
  const uint64_t points = reader.level(0).header.points;
  const std::string what = reader.file().path + ", level 0";
  GTN_ASSIGN_OR_RETURN(MergeTreeHeader h, readMergeTreeHeader(*payload, points, what));
  if (h.version >= 3) return h.free_merges;
  GTN_ASSIGN_OR_RETURN(MergeTree tree, decodeMergeTree(*payload, points, what, nullptr));
  return leadingFreeMerges(tree);
}

StatusOr<uint64_t> mergesForRatio(GtnReader& reader, double ratio) {
  if (reader.levels() == 0 || !(ratio > 0)) return uint64_t{0};
  const uint64_t points = reader.level(0).header.points;
  GTN_ASSIGN_OR_RETURN(const uint64_t free, levelZeroUnreferencedMerges(reader));
  return free + static_cast<uint64_t>(std::llround(std::min(1.0, ratio) * static_cast<double>(points - free)));
}

namespace {
// levelMergeTree with level i's payload read already, and its header.
StatusOr<LevelTree> levelMergeTreeOf(GtnReader& reader, size_t i, uint64_t max_merges, const DecodeFields* fields,
                                     const std::vector<uint8_t>& payload, const MergeTreeHeader& h) {
  const std::string what = reader.file().path + ", level " + std::to_string(i);
  const uint64_t points = reader.level(i).header.points;
  LevelTree out;
  out.level = i;
  std::vector<uint32_t> ids;  // the next level's ids of the level's vertices, where the tree needs them
  if ((h.needs_mesh || h.needs_next_ids) && max_merges > 0) {
    out.decoded = std::make_unique<TetMeshBuilder>();
    GTN_RETURN_IF_ERROR(reader.decodeLevel(i, *out.decoded, nullptr, fields, h.needs_next_ids ? &ids : nullptr));
  }
  GTN_ASSIGN_OR_RETURN(out.tree, decodeMergeTree(payload, points, what, out.decoded ? &out.decoded->mesh() : nullptr,
                                                 max_merges, h.needs_next_ids ? &ids : nullptr));
  return out;
}
}  // namespace

StatusOr<LevelTree> levelMergeTree(GtnReader& reader, size_t i, uint64_t max_merges, const DecodeFields* fields) {
  const std::string what = reader.file().path + ", level " + std::to_string(i);
  GTN_ASSIGN_OR_RETURN(auto payload, reader.mergeTreePayload(i));
  if (!payload) return usageError(what + " stores no merge tree: cannot simplify beyond the stored levels");
  GTN_ASSIGN_OR_RETURN(MergeTreeHeader h, readMergeTreeHeader(*payload, reader.level(i).header.points, what));
  return levelMergeTreeOf(reader, i, max_merges, fields, *payload, h);
}

Status emitLevel(GtnReader& reader, const LevelTree& level, MeshSink& sink, const DecodeFields* fields) {
  if (!level.decoded) return reader.decodeLevel(level.level, sink, nullptr, fields);
  return replayLevel(level.decoded->header(), level.decoded->mesh(), level.decoded->boundary(), sink);
}

namespace {

// The merges to apply from a level's tree: the plan's, or where `clamp`, at most the tree's (a ratio
// beyond what the tree allows gets the coarsest mesh); a usage error where the tree has fewer.
Status fitPlanToTree(GtnReader& reader, const MergeTree& tree, uint64_t target_merges, bool clamp, SimplifyPlan& plan,
                     SimplifyPlan* plan_out) {
  if (plan.extra_merges > tree.merges && clamp) {
    plan.extra_merges = tree.merges;
    if (plan_out) *plan_out = plan;
  }
  if (plan.extra_merges > tree.merges)
    return usageError(reader.file().path + ": " + std::to_string(target_merges) +
                      " merges requested, the merge tree has " +
                      std::to_string(reader.level(plan.level).header.merges + tree.merges) + " in all");
  return Status::ok();
}

// A StreamSimplifier made when the level's first event arrives, from a merge tree decoded on another
// thread meanwhile: `ready()` waits for it and gives it (or its failure). A structured piece decodes
// its streams before its first event, so its streams and the tree decode side by side.
class SimplifierOnceTreeIsReady : public MeshSink {
 public:
  SimplifierOnceTreeIsReady(std::function<StatusOr<const MergeTree*>()> ready, const SimplifyPlan& plan, MeshSink& out)
      : ready_(std::move(ready)), plan_(plan), out_(out) {}
  Status beginLevel(const LevelHeader& header) override {
    GTN_ASSIGN_OR_RETURN(const MergeTree* tree, ready_());
    filter_.emplace(*tree, plan_.extra_merges, out_);
    return filter_->beginLevel(header);
  }
  Status vertex(uint32_t id, const double xyz[3], const uint8_t* values) override {
    GTN_RETURN_IF_ERROR(begun());
    return filter_->vertex(id, xyz, values);
  }
  Status boundaryTriangle(const uint32_t v[3]) override {
    GTN_RETURN_IF_ERROR(begun());
    return filter_->boundaryTriangle(v);
  }
  Status endBoundary() override {
    GTN_RETURN_IF_ERROR(begun());
    return filter_->endBoundary();
  }
  Status tet(const uint32_t v[4], const uint8_t* cell_values) override {
    GTN_RETURN_IF_ERROR(begun());
    return filter_->tet(v, cell_values);
  }
  Status retireVertex(uint32_t id) override {
    GTN_RETURN_IF_ERROR(begun());
    return filter_->retireVertex(id);
  }
  Status endLevel() override {
    GTN_RETURN_IF_ERROR(begun());
    return filter_->endLevel();
  }
  bool takesWholeLevel() const override { return out_.takesWholeLevel(); }
  Status wholeLevel(const LevelHeader& header, TetMesh&& mesh,
                    std::vector<std::array<uint32_t, 3>>&& boundary) override {
    GTN_ASSIGN_OR_RETURN(const MergeTree* tree, ready_());
    filter_.emplace(*tree, plan_.extra_merges, out_);
    return filter_->wholeLevel(header, std::move(mesh), std::move(boundary));
  }

 private:
  Status begun() const {
    return filter_ ? Status::ok() : invalidData("simplification: a level's event before its beginning");
  }
  std::function<StatusOr<const MergeTree*>()> ready_;
  const SimplifyPlan& plan_;
  MeshSink& out_;
  std::optional<StreamSimplifier> filter_;
};

}  // namespace

Status streamSimplified(GtnReader& reader, uint64_t target_merges, MeshSink& sink, SimplifyPlan* plan_out, bool clamp,
                        const DecodeFields* fields) {
  GTN_ASSIGN_OR_RETURN(SimplifyPlan plan, planSimplification(reader, target_merges));
  if (plan_out) *plan_out = plan;
  if (plan.extra_merges == 0) return reader.decodeLevel(plan.level, sink, nullptr, fields);
  const std::string what = reader.file().path + ", level " + std::to_string(plan.level);
  // A tree that decodes without its level (a grid's, whose parents are grid places) is decoded on
  // another thread while the level is: the payload is read here (the reader is used by one thread
  // at a time), and the level's first event waits for the tree.
  GTN_ASSIGN_OR_RETURN(auto payload, reader.mergeTreePayload(plan.level));
  if (!payload) return usageError(what + " stores no merge tree: cannot simplify beyond the stored levels");
  const uint64_t points = reader.level(plan.level).header.points;
  GTN_ASSIGN_OR_RETURN(MergeTreeHeader h, readMergeTreeHeader(*payload, points, what));
  if (!h.needs_mesh && !h.needs_next_ids) {
    std::optional<StatusOr<MergeTree>> tree;
    tbb::task_group decoding;
    const WaitOnExit join{decoding};
    decoding.run([&] { tree = decodeMergeTree(*payload, points, what, nullptr, plan.extra_merges); });
    bool waited = false;
    auto ready = [&]() -> StatusOr<const MergeTree*> {
      decoding.wait();
      waited = true;
      if (!tree->isOk()) return tree->status();
      GTN_RETURN_IF_ERROR(fitPlanToTree(reader, **tree, target_merges, clamp, plan, plan_out));
      return &**tree;
    };
    SimplifierOnceTreeIsReady filter(ready, plan, sink);
    Status st = reader.decodeLevel(plan.level, filter, nullptr, fields);
    // The tree's failure first, as when the tree was decoded before the level.
    decoding.wait();
    if (!tree->isOk()) return tree->status();
    if (!waited) GTN_RETURN_IF_ERROR(fitPlanToTree(reader, **tree, target_merges, clamp, plan, plan_out));
    return st;
  }
  GTN_ASSIGN_OR_RETURN(LevelTree level, levelMergeTreeOf(reader, plan.level, plan.extra_merges, fields, *payload, h));
  GTN_RETURN_IF_ERROR(fitPlanToTree(reader, level.tree, target_merges, clamp, plan, plan_out));
  StreamSimplifier filter(level.tree, plan.extra_merges, sink);
  return emitLevel(reader, level, filter, fields);
}

}  // namespace gtn
