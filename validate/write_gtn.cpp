#include "validate/write_gtn.h"

#include <optional>

#include <tbb/task_group.h>

#include "codec/grid_coder.h"
#include "codec/pieces.h"
#include "mesh/wait_on_exit.h"
#include "simplify/levels.h"
#include "validate/mesh_checks.h"

namespace gtn {

namespace {
// A mesh with errors of its own would make a file that `gtn validate` calls invalid: refused before
// anything is written, unless the caller keeps it (then stored as it is, and said so).
Status refuseOrWarnOfLevel0Errors(LevelStructureCheck& check, const GtnConvertOptions& o, const std::string& source,
                                  std::vector<std::string>* warnings) {
  const std::string errors = check.level0Errors();
  if (errors.empty()) return Status::ok();
  if (!o.keep_invalid)
    return invalidData(source + ": the mesh has errors that `gtn validate` would report on the file (" + errors +
                       "); nothing was written (--keep-invalid writes it as it is)");
  if (warnings)
    warnings->push_back(source + ": the mesh has errors that `gtn validate` reports on the file too (" + errors +
                        "); it is stored as it is (--keep-invalid)");
  return Status::ok();
}

// A grid's tetrahedra released (GtnConvertOptions::release_grid_tets) and made again from its
// layout: by restore() where level 0 needs them back before the file is written, else as
// writeLevels returns (on an error too).
class ReleasedTets {
 public:
  ReleasedTets(TetMesh* mesh, GridLayout layout) : mesh_(mesh), layout_(std::move(layout)), tets_(layout_) {
    std::vector<Tet>().swap(mesh_->tets);
  }
  ReleasedTets(const ReleasedTets&) = delete;
  ReleasedTets& operator=(const ReleasedTets&) = delete;
  ~ReleasedTets() { restore(); }
  const RuleGridTets& tets() const { return tets_; }
  void restore() {
    if (mesh_) mesh_->tets = gridTets(layout_);
    mesh_ = nullptr;
  }

 private:
  TetMesh* mesh_;
  GridLayout layout_;
  RuleGridTets tets_;
};

// The layout of `mesh` where it is one grid of rule cells, the block from point 0 with no alias and
// no exception, whose tetrahedra RuleGridTets makes exactly (checked, tetrahedron by tetrahedron).
std::optional<GridLayout> ruleGridOf(const TetMesh& mesh) {
  if (mesh.blocks.size() != 1) return std::nullopt;
  const StructuredBlock& b = mesh.blocks[0];
  const uint64_t nodes = uint64_t{b.dims[0]} * b.dims[1] * b.dims[2];
  if (b.first_point != 0 || !b.aliases.empty() || nodes != mesh.numPoints()) return std::nullopt;
  StatusOr<GridLayout> layout = matchGridLayout(mesh, b.dims);
  if (!layout.isOk() || !layout->aliases.empty() || !layout->exceptions.empty()) return std::nullopt;
  if (!RuleGridTets(*layout).sameAs(mesh.tets)) return std::nullopt;
  return std::move(layout).value();
}

Status writeLevels(const std::string& path, const TetMesh& mesh, TetMesh* owned, const GtnConvertOptions& o,
                   const GtnWriteOptions& wo, const std::string& source, std::vector<std::string>* warnings) {
  // Mip levels are made from the merge tree and checked against it (a validator reports levels without
  // one): without a tree, level 0 alone.
  if (!o.merge_tree && o.levels > 0)
    return usageError(source + ": " + std::to_string(o.levels) +
                      " mip level(s) asked for with no merge tree: mip levels are stored with the merge tree "
                      "they are checked against");
  if (!o.merge_tree) {
    GtnLevelInput level0;
    level0.mesh = &mesh;
    if (wo.verify) {
      // Encoded first: a mesh the encoder cannot store (non-manifold faces, say) is refused for that,
      // not offered --keep-invalid.
      GTN_ASSIGN_OR_RETURN(PiecedLevel encoded, encodePieces(mesh, EncodeOptions{}, wo.piece_tets));
      level0.encoded = std::make_shared<PiecedLevel>(std::move(encoded));
      LevelStructureCheck structure(mesh, path);
      GTN_RETURN_IF_ERROR(refuseOrWarnOfLevel0Errors(structure, o, source, warnings));
    }
    return writeGtnFile(path, {level0}, wo);
  }
  reportProgress(wo.progress, "rank merges", 0.0);
  GTN_RETURN_IF_ERROR(checkRankingOptions(mesh, o.ranking));
  // Level 0 is encoded while the merges are ranked, beside the ranking's tail (the coarse rounds of
  // few parts and the whole mesh's queue, one thread's work, after the rounds of parts that keep every
  // thread busy): on another thread where TBB has one, after the ranking where it has not. A level 0
  // that fails to encode fails the conversion then, before its own errors are looked at (the
  // encoder's refusal says why no option stores it). Where mip levels will be checked, level 0's own
  // errors (the ones a mip level may keep) are found next, by the same task: the encoding and the
  // check each hold a face adjacency's worth of memory or more, and the two at once beside the
  // ranking were a large convert's peak. The tail comes after the fine rounds of many parts (the
  // encoding beside the first round took a thread from it). A large grid whose tetrahedra are
  // released (below) has both done before the ranking instead, while they are there.
  LevelStructureCheck structure(mesh, path);
  const bool check_level0 = wo.verify && o.levels != 0;
  std::shared_ptr<PiecedLevel> level0;
  Status encoded = Status::ok();
  // Waited for on every return from here (`structure` must outlive it).
  tbb::task_group encoding;
  const WaitOnExit join_encoding{encoding};
  bool encoding_level0 = false;
  auto encodeLevel0 = [&] {
    if (encoding_level0) return;
    encoding_level0 = true;
    encoding.run([&] {
      auto e = encodePieces(mesh, EncodeOptions{}, wo.piece_tets);
      if (!e.isOk()) {
        encoded = e.status();
        return;
      }
      level0 = std::make_shared<PiecedLevel>(std::move(e).value());
      if (check_level0) structure.checkLevel0();
    });
  };
  RankingStats ranked;
  RankingOptions ranking_options = o.ranking;
  ranking_options.beside_ranking_tail = encodeLevel0;
  // A large grid of rule cells: level 0 encoded and checked first, then its tetrahedra released until
  // the file is written (GtnConvertOptions::release_grid_tets).
  std::optional<ReleasedTets> released;
  RankingFaces grid_faces;
  if (owned == &mesh && mesh.numTets() >= o.release_grid_tets && !o.ranking.grid_tets) {
    if (std::optional<GridLayout> layout = ruleGridOf(mesh)) {
      encodeLevel0();
      encoding.wait();
      GTN_RETURN_IF_ERROR(encoded);
      if (level0 && level0->isGrid()) {
        grid_faces = rankingFaces(mesh);
        released.emplace(owned, std::move(*layout));
        ranking_options.faces = &grid_faces;
        ranking_options.grid_tets = &released->tets();
      }
    }
  }
  StatusOr<MergeTree> ranking = rankMerges(mesh, ranking_options, &ranked, wo.progress);
  if (released) ranked.faces = std::move(grid_faces);  // the batches read them from there
  encodeLevel0();                                      // where the ranking did not start it
  // The check's face adjacency beside the batches was a convert's peak of memory: the check ends
  // before them.
  encoding.wait();
  GTN_RETURN_IF_ERROR(encoded);
  if (!ranking.isOk()) return ranking.status();
  MergeTree tree = std::move(ranking).value();
  MergeTreeForm level0_form;
  if (o.merge_tree && level0) {
    reportProgress(wo.progress, "batch merges", 0.0);
    GTN_ASSIGN_OR_RETURN(StoredMergeTree stored,
                         storedMergeTree(mesh, tree, *level0, &ranked, released ? &released->tets() : nullptr));
    tree = std::move(stored.tree);
    level0_form = stored.level0_form;
    ranked.rounds = {};
    ranked.faces = {};
  }
  // Level 0's tetrahedra: the mesh's, or made from their indices while they are released.
  const RuleGridTets* tets0 = released ? &released->tets() : nullptr;
  const uint64_t tet_count = tets0 ? tets0->size() : mesh.numTets();
  if (const std::string note = defaultFieldNote(ranked); !note.empty() && warnings)
    warnings->push_back(source + ": " + note);
  LevelOptions lo;
  lo.levels = o.levels;
  lo.merge_tree = o.merge_tree;
  // The levels are made one at a time as the writer comes to them (a level past the first one beyond
  // the storage bound is never made), and each level written is checked where the writer verifies it
  // (part of the verification: every level the simplifier made and the file stores is a valid mesh).
  // The first level past the bound is made and encoded (its bytes decide) but not checked.
  GTN_ASSIGN_OR_RETURN(MipLevelBuilder levels, MipLevelBuilder::create(mesh, tree, lo, tets0));
  const size_t count = levels.count();
  // Levels stop where the merge tree does (a small or flat mesh has few merges): say so rather than
  // write fewer levels than asked for without a word.
  if (o.levels > 0 && count - 1 < static_cast<size_t>(o.levels) && warnings)
    warnings->push_back(source + ": --levels " + std::to_string(o.levels) + ": the merge tree has " +
                        std::to_string(tree.merges) + " merge(s) of " + std::to_string(mesh.numPoints()) +
                        " points, enough for " + std::to_string(count - 1) + " level(s) beyond level 0");
  GtnWriteOptions bounded = wo;
  if (o.levels < 0) bounded.level_storage_limit = o.level_storage;
  // Automatic levels beside a structured level 0: only the coarse levels that read faster than level 0
  // simplified on the fly (kStructuredLevelShare).
  size_t first = 1;
  if (o.levels < 0 && count > 1 && level0 && level0->isGrid()) {
    // The share counts the levels below the floor of automatic levels too (LevelOptions::min_tets),
    // which are not stored: the floor leaves out levels, it does not let a finer one in.
    LevelOptions unfloored = lo;
    unfloored.min_tets = 0;
    GTN_ASSIGN_OR_RETURN(MipLevelBuilder all, MipLevelBuilder::create(mesh, tree, unfloored, tets0));
    uint64_t chain = 0;
    first = count;
    for (size_t i = all.count(); i-- > 1;) {
      chain += all.tetsOf(i);
      if (chain * kStructuredLevelShare > tet_count) break;
      first = std::min(i, count);
    }
    // The finer levels are never made: the first stored one comes from level 0 in one pass.
    if (first < count) levels.skipTo(first);
  }
  std::vector<size_t> kept = {0};
  for (size_t i = first; i < count; ++i) kept.push_back(i);
  std::vector<GtnLevelInput> inputs(kept.size());
  for (size_t k = 0; k < kept.size(); ++k) {
    const size_t i = kept[k];
    GtnLevelInput& in = inputs[k];
    in.merges = levels.merges()[i];
    in.ratio = levels.ratios()[i];
    if (i == 0) {
      in.mesh = &mesh;
      in.encoded = std::move(level0);
    } else {
      // A level keeps about as many tetrahedra per point as level 0 (progress only).
      in.expected_tets = mesh.numPoints() == 0
                             ? 0
                             : static_cast<uint64_t>(static_cast<double>(tet_count) *
                                                     static_cast<double>(mesh.numPoints() - in.merges) /
                                                     static_cast<double>(mesh.numPoints()));
      in.make_mesh = [&, i]() -> StatusOr<const TetMesh*> {
        reportProgress(wo.progress, "build level " + std::to_string(i) + " (" + std::to_string(count) + " levels)");
        return levels.level(i);
      };
      in.check_mesh = [&, i](const TetMesh& level) {
        reportProgress(wo.progress, "check level " + std::to_string(i) + " (" + std::to_string(count) + " levels)");
        return structure.check(level, i);
      };
    }
    if (o.merge_tree) {
      // Level i's tree, its first `merges` merges; `next_index` where the level names the next level's
      // vertices.
      auto encodeTree = [&, i](const std::vector<uint32_t>& vertex_order, uint64_t merges,
                               const std::vector<uint32_t>* next_index) -> StatusOr<std::vector<uint8_t>> {
        const std::shared_ptr<const MergeTree> t = levels.tree(i);
        if (!t) return usageError(path + ": level " + std::to_string(i) + "'s merge tree asked for before the level");
        const TetMesh* level_mesh = &mesh;
        if (i > 0) {
          GTN_ASSIGN_OR_RETURN(level_mesh, levels.level(i));
        }
        MergeTreeForm form = i == 0 ? level0_form : MergeTreeForm{};
        form.next_index = next_index;
        return encodeMergeTree(merges < t->merges ? prefixTree(*t, merges) : *t, vertex_order, level_mesh, form);
      };
      in.merge_tree_prefix = [encodeTree](const std::vector<uint32_t>& vertex_order, uint64_t merges,
                                          const std::vector<uint32_t>& next_index) {
        return encodeTree(vertex_order, merges, &next_index);
      };
      in.merge_tree = [encodeTree](const std::vector<uint32_t>& vertex_order) {
        return encodeTree(vertex_order, UINT64_MAX, nullptr);
      };
    }
    if (k + 1 < kept.size() && kept[k + 1] == i + 1)  // the next stored level is the next one
      in.next_index = [&, i]() -> StatusOr<std::vector<uint32_t>> {
        GTN_RETURN_IF_ERROR(levels.level(i + 1).status());
        return levels.nextIndex(i);
      };
  }
  // Released tetrahedra stay so while the file is written, unless level 0 may name the next level's
  // vertices (the writer would encode it again from the mesh); the writer reads them from the grid,
  // and this function keeps a reference to level 0's encoding, so that the writer copies it rather
  // than encode the mesh.
  std::shared_ptr<PiecedLevel> level0_held;
  if (released && inputs[0].next_index) released->restore();
  if (released && mesh.tets.empty()) {
    level0_held = inputs[0].encoded;
    inputs[0].grid_tets = tets0;
  }
  // Level 0's own errors (checked on another thread meanwhile) decide before anything is written.
  if (wo.verify) GTN_RETURN_IF_ERROR(refuseOrWarnOfLevel0Errors(structure, o, source, warnings));
  Status written = writeGtnFile(path, inputs, bounded);
  level0_held.reset();
  inputs.clear();
  return written;
}
}  // namespace

StatusOr<StoredMergeTree> storedMergeTree(const TetMesh& mesh, const MergeTree& ranked, const PiecedLevel& level0,
                                          const RankingStats* ranking, const RuleGridTets* grid_tets) {
  // A structured level 0 (a grid, never naming the next level's vertices) stores the whole tree, which
  // readers decode to simplify it on the fly at every ratio finer than the stored levels: its parents
  // are coded as grid places (the block's dims and the decoding ids decide the candidates), or as
  // deltas where the block's nodes are not its first decoding ids (aliases), neither of which needs
  // anything of the level, and its batches are ordered by decoding id. Candidates against the level
  // decode at about 2.5 us a merge, which made a grid's on-the-fly read three times slower than the
  // level's own decode and simplification. Every other level codes its parents as candidates, and its
  // batches are ordered by position.
  StoredMergeTree out;
  const bool structured = level0.isGrid();
  out.level0_form.candidates = !structured;
  if (structured && level0.vertex_order.size() != mesh.numPoints())
    return invalidData("storedMergeTree: level 0's vertex order does not match the mesh");
  if (structured && mesh.blocks.size() == 1 && mesh.blocks[0].first_point == 0 && mesh.blocks[0].aliases.empty()) {
    const StructuredBlock& b = mesh.blocks[0];
    const uint64_t nodes = uint64_t{b.dims[0]} * b.dims[1] * b.dims[2];
    bool in_order = nodes > 0 && nodes <= mesh.numPoints();
    for (uint64_t g = 0; in_order && g < nodes; ++g) in_order = level0.vertex_order[g] == g;
    if (in_order) out.level0_form.grid = {b.dims[0], b.dims[1], b.dims[2]};
  }
  // A structured level's keys come from its decoding ids as the batches read them (no array of them).
  std::vector<uint64_t> point_keys;
  if (!structured) {
    point_keys.resize(mesh.numPoints());
    for (size_t v = 0; v < point_keys.size(); ++v) point_keys[v] = batchKeyOfPoint(mesh.point(v));
  }
  const BatchKeys keys = structured ? BatchKeys::ofIds(level0.vertex_order) : BatchKeys(point_keys);
  static const std::vector<RankingRound> kNoRounds;
  GTN_ASSIGN_OR_RETURN(
      out.tree, batchMerges(mesh, ranked, keys, kDefaultBatchDivisor, nullptr, ranking ? ranking->rounds : kNoRounds,
                            ranking ? &ranking->faces : nullptr, grid_tets));
  return out;
}

namespace {
Status writeWithLevels(const std::string& path, const TetMesh& mesh, TetMesh* owned, const GtnConvertOptions& options,
                       const GtnWriteOptions& write_options, const std::string& source,
                       std::vector<std::string>* warnings) {
  Status st = writeLevels(path, mesh, owned, options, write_options, source, warnings);
  // The encoder's refusals are about the mesh: name it.
  if (!st.isOk() && st.message().rfind("encodeLevel: ", 0) == 0)
    st = Status(st.code(), source + ": cannot be encoded: " + st.message().substr(13));
  return st;
}
}  // namespace

Status writeGtnWithLevels(const std::string& path, const TetMesh& mesh, const GtnConvertOptions& options,
                          const GtnWriteOptions& write_options, const std::string& source,
                          std::vector<std::string>* warnings) {
  return writeWithLevels(path, mesh, nullptr, options, write_options, source, warnings);
}

Status writeGtnWithLevels(const std::string& path, TetMesh* mesh, const GtnConvertOptions& options,
                          const GtnWriteOptions& write_options, const std::string& source,
                          std::vector<std::string>* warnings) {
  return writeWithLevels(path, *mesh, mesh, options, write_options, source, warnings);
}

}  // namespace gtn
