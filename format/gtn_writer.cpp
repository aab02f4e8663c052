#include <cerrno>
#include <cstdio>
#include <cstring>

#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include <optional>

#include "codec/level_check.h"
#include "codec/pieces_check.h"
#include "format/file_io.h"
#include "format/gtn_file.h"
#include "mesh/wait_on_exit.h"

namespace gtn {

namespace {
// An unstructured piece's codec streams in PIEC order (spec section 7.2).
std::vector<const std::vector<uint8_t>*> pieceStreams(const EncodedLevel& e) {
  std::vector<const std::vector<uint8_t>*> out = {&e.boundary, &e.connectivity, &e.geometry};
  for (const auto& s : e.point_fields) out.push_back(&s);
  for (const auto& s : e.cell_fields) out.push_back(&s);
  return out;
}

bool sameFields(const std::vector<FieldDesc>& a, const std::vector<FieldDesc>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (a[i].name != b[i].name || a[i].components != b[i].components || a[i].type != b[i].type) return false;
  return true;
}
}  // namespace

GtnStreamWriter::GtnStreamWriter(Output out, GtnWriteOptions options)
    : out_(std::move(out)), options_(std::move(options)) {}

Status GtnStreamWriter::emit(ChunkTag tag, std::span<const uint8_t> payload, bool ancillary, bool try_zstd) {
  scratch_.clear();
  appendGtnChunk(scratch_, tag, payload, ancillary, try_zstd && options_.zstd, kGtnZstdLevel);
  if (begun_ && levels_written_ > 0 && !directory_.empty() && tag != kTagDirectory && tag != kTagEnd)
    directory_.back().push_back({tag, offset_, scratch_.size()});
  GTN_RETURN_IF_ERROR(out_(scratch_));
  offset_ += scratch_.size();
  return Status::ok();
}

Status GtnStreamWriter::begin(const LevelHeader& level0, uint64_t level_count) {
  if (begun_) return usageError("GtnStreamWriter::begin called twice");
  if (level_count == 0 || level_count > kGtnMaxLevels)
    return usageError("a .gtn file holds 1 to " + std::to_string(kGtnMaxLevels) + " levels, not " +
                      std::to_string(level_count));
  if (!isFloatType(level0.coord_type)) return usageError("coordinates must be float32 or float64");
  for (const auto* fields : {&level0.point_fields, &level0.cell_fields}) {
    if (fields->size() > kGtnMaxFields) return usageError("more than " + std::to_string(kGtnMaxFields) + " fields");
    for (const FieldDesc& f : *fields)
      if (f.components == 0 || f.components > kGtnMaxComponents)
        return usageError("field '" + f.name + "' has " + std::to_string(f.components) + " components (1 to " +
                          std::to_string(kGtnMaxComponents) + " allowed)");
  }
  level0_ = level0;
  level_count_ = level_count;
  const auto prefix = encodeGtnPrefix();
  GTN_RETURN_IF_ERROR(out_(prefix));
  offset_ = prefix.size();
  GtnFileHeader h;
  h.writer_flags = options_.directory ? kGhdrHasDirectory : 0;
  h.level_count = level_count;
  h.points = level0.points;
  h.tets = level0.tets;
  h.draft = kGtnDraftRevision;
  h.piece_tets = options_.piece_tets;
  h.coord_type = level0.coord_type;
  h.point_fields = level0.point_fields;
  h.cell_fields = level0.cell_fields;
  for (int i = 0; i < 3; ++i) {
    h.bbox_min[i] = level0.bbox_min[i];
    h.bbox_max[i] = level0.bbox_max[i];
  }
  h.tool_version = options_.tool_version;
  h.command_line = options_.command_line;
  h.metadata = level0.metadata;
  record_context_ = levelRecordContext(h);
  begun_ = true;
  return emit(kTagFileHeader, encodeFileHeader(h), false, true);
}

Status GtnStreamWriter::addLevel(const EncodedLevel& e, double ratio,
                                 const std::optional<std::vector<uint8_t>>& merge_tree) {
  return addLevel(onePieceLevel(e), ratio, merge_tree);
}

Status GtnStreamWriter::addLevel(const PiecedLevel& l, double ratio,
                                 const std::optional<std::vector<uint8_t>>& merge_tree) {
  if (!begun_ || finished_) return usageError("GtnStreamWriter::addLevel outside begin/finish");
  const LevelHeader& h = l.header;
  if (levels_written_ >= level_count_)
    return usageError("more levels than the " + std::to_string(level_count_) + " declared");
  if (h.level != levels_written_)
    return usageError("level " + std::to_string(h.level) + " given where level " + std::to_string(levels_written_) +
                      " comes next");
  const std::string level = "level " + std::to_string(h.level);
  if (h.coord_type != level0_.coord_type || !sameFields(h.point_fields, level0_.point_fields) ||
      !sameFields(h.cell_fields, level0_.cell_fields))
    return usageError(level +
                      " has a different coordinate type or field list than level 0; all levels must share them");
  if (h.level == 0 && (h.points != level0_.points || h.tets != level0_.tets))
    return usageError("level 0's counts differ from those given to begin()");
  if (l.pieces.empty() || l.pieces.size() > kGtnMaxPieces || l.encoded.size() != l.pieces.size())
    return usageError(level + " has " + std::to_string(l.pieces.size()) + " pieces and " +
                      std::to_string(l.encoded.size()) + " piece encodings (1 to " + std::to_string(kGtnMaxPieces) +
                      " pieces, one encoding each)");
  if ((l.pieces.size() == 1) != l.classes.empty() || l.seam_streams.size() != l.classes.size())
    return usageError(level + ": seam classes go with several pieces, one stream each");
  uint64_t tets = 0;
  for (size_t p = 0; p < l.pieces.size(); ++p) {
    const EncodedLevel& e = l.encoded[p];
    if (l.pieces[p].kind != kPieceUnstructured && !(l.pieces[p].kind == kPieceStructured && l.pieces.size() == 1))
      return usageError(level + " piece " + std::to_string(p) + ": kind " + std::to_string(l.pieces[p].kind) +
                        " (a structured piece must be its level's only piece)");
    if (e.point_fields.size() != h.point_fields.size() || e.cell_fields.size() != h.cell_fields.size())
      return usageError(level + ": the number of field streams does not match the header");
    tets += l.pieces[p].tets;
  }
  if (l.pieces.size() == 1 && (l.pieces[0].points != h.points || l.pieces[0].own_points != h.points))
    return usageError(level + ": its one piece must hold all its points as its own");
  if (tets != h.tets)
    return usageError(level + ": the pieces' tetrahedra sum to " + std::to_string(tets) + ", not " +
                      std::to_string(h.tets));
  if (!(ratio >= 0.0 && ratio <= 1.0)) return usageError("level ratio must be in [0, 1]");
  if (h.level == 0 && h.merges != 0) return usageError("level 0 must have 0 merges");
  if (l.base > 1 ||
      (l.base == 1 && (l.pieces.size() != 1 || l.pieces[0].kind != kPieceUnstructured || h.level + 1 >= level_count_)))
    return usageError(level + ": a level that names the next level's vertices must be one unstructured piece " +
                      "and not the last level");

  ++levels_written_;
  if (options_.directory) directory_.emplace_back();
  GtnLevelRecord r;
  r.level = h.level;
  r.merges = h.merges;
  r.ratio = ratio;
  r.points = h.points;
  r.tets = h.tets;
  r.boundary_triangles = h.boundary_triangles;
  for (int i = 0; i < 3; ++i) {
    r.bbox_min[i] = h.bbox_min[i];
    r.bbox_max[i] = h.bbox_max[i];
  }
  r.pieces = l.pieces;
  r.streams.resize(l.pieces.size());
  for (size_t p = 0; p < l.encoded.size(); ++p)
    if (l.pieces[p].kind == kPieceUnstructured)
      for (const std::vector<uint8_t>* s : pieceStreams(l.encoded[p])) r.streams[p].push_back(s->size());
  r.base = l.base;
  GTN_RETURN_IF_ERROR(emit(kTagLevelHeader, encodeLevelRecord(r, record_context_), false, false));
  record_context_ = nextLevelRecordContext(record_context_, r);
  if (l.pieces.size() > 1) GTN_RETURN_IF_ERROR(emit(kTagSeam, encodeSeamTable(l.classes, l.seam_streams), false, true));
  std::vector<uint8_t> piece;
  for (size_t p = 0; p < l.encoded.size(); ++p) {
    const EncodedLevel& e = l.encoded[p];
    if (l.pieces[p].kind == kPieceStructured) {
      GTN_RETURN_IF_ERROR(emit(kTagGrid, e.connectivity, false, true));
      continue;
    }
    piece.clear();
    for (const std::vector<uint8_t>* s : pieceStreams(e)) piece.insert(piece.end(), s->begin(), s->end());
    GTN_RETURN_IF_ERROR(emit(kTagPiece, piece, false, true));
  }
  if (merge_tree) GTN_RETURN_IF_ERROR(emit(kTagMergeTree, *merge_tree, true, true));
  return Status::ok();
}

Status GtnStreamWriter::addChunk(ChunkTag tag, std::span<const uint8_t> payload, bool ancillary) {
  if (!begun_ || finished_) return usageError("GtnStreamWriter::addChunk outside begin/finish");
  return emit(tag, payload, ancillary, true);
}

Status GtnStreamWriter::finish() {
  if (!begun_ || finished_) return usageError("GtnStreamWriter::finish called twice or before begin");
  if (levels_written_ != level_count_)
    return usageError(std::to_string(levels_written_) + " levels written, " + std::to_string(level_count_) +
                      " declared");
  GtnTrailer t;
  if (options_.directory) {
    t.directory_offset = offset_;
    const uint64_t before = offset_;
    GTN_RETURN_IF_ERROR(emit(kTagDirectory, encodeDirectory(directory_), true, true));
    t.directory_size = offset_ - before;
  }
  GTN_RETURN_IF_ERROR(emit(kTagEnd, encodeTrailer(t), false, false));
  finished_ = true;
  return Status::ok();
}

GtnStreamWriter::Output fileOutput(std::FILE* f) {
  return [f](std::span<const uint8_t> b) -> Status {
    if (!b.empty() && std::fwrite(b.data(), 1, b.size(), f) != b.size())
      return ioError(std::string("write failed: ") + std::strerror(errno));
    return Status::ok();
  };
}

Status namedByOutput(const std::string& path, Status st) {
  if (st.isOk()) return st;
  return Status(st.code(), (path == "-" ? std::string("standard output") : path) + ": " + st.message());
}

StatusOr<std::vector<uint8_t>> assembleGtn(const std::vector<const EncodedLevel*>& levels,
                                           const GtnWriteOptions& options, const std::vector<double>& ratios,
                                           const std::vector<std::optional<std::vector<uint8_t>>>& merge_trees) {
  if (levels.empty()) return usageError("no level to write");
  std::vector<uint8_t> bytes;
  GtnStreamWriter w(
      [&](std::span<const uint8_t> b) {
        bytes.insert(bytes.end(), b.begin(), b.end());
        return Status::ok();
      },
      options);
  GTN_RETURN_IF_ERROR(w.begin(levels[0]->header, levels.size()));
  for (size_t i = 0; i < levels.size(); ++i) {
    GTN_RETURN_IF_ERROR(w.addLevel(*levels[i], i < ratios.size() ? ratios[i] : 0.0,
                                   i < merge_trees.size() ? merge_trees[i] : std::nullopt));
  }
  GTN_RETURN_IF_ERROR(w.finish());
  return bytes;
}

namespace {

struct EncodedInput {
  PiecedLevel level;
  std::optional<std::vector<uint8_t>> tree;
};

// Level i's index and merges, in its header and its pieces'.
void setLevelIndex(PiecedLevel& level, size_t i, uint64_t merges) {
  level.header.level = static_cast<uint32_t>(i);
  level.header.merges = merges;
  for (EncodedLevel& e : level.encoded) {
    e.header.level = static_cast<uint32_t>(i);
    e.header.merges = merges;
  }
}

StatusOr<EncodedInput> encodeInput(const std::vector<GtnLevelInput>& levels, size_t i, const TetMesh& mesh,
                                   const GtnWriteOptions& options) {
  EncodedInput out;
  const std::shared_ptr<PiecedLevel>& given = levels[i].encoded;
  if (given && !given->encoded.empty()) {
    // Taken over where nothing else holds it (level 0's encoding is as large as the level's file).
    if (given.use_count() == 1) {
      out.level = std::move(*given);
      given->encoded.clear();
    } else {
      out.level = *given;
    }
  } else {
    GTN_ASSIGN_OR_RETURN(out.level, encodePieces(mesh, EncodeOptions{}, options.piece_tets));
  }
  setLevelIndex(out.level, i, levels[i].merges);
  if (levels[i].merge_tree) {
    auto t = levels[i].merge_tree(out.level.vertex_order);
    if (!t.isOk()) return t.status();
    out.tree = std::move(t).value();
  }
  return out;
}

// With options.verify: level i passes its own check_mesh and decodes back to its mesh (otherwise the
// simplifier or the encoder has a bug, and the file must not replace anything).
Status checkDecodesBack(const std::string& path, const GtnLevelInput& level, const TetMesh& mesh, size_t i,
                        const PiecedLevel& e, const GtnWriteOptions& options) {
  if (!options.verify) return Status::ok();
  if (level.check_mesh) GTN_RETURN_IF_ERROR(level.check_mesh(mesh));
  const std::string why = piecedLosslessMismatch(mesh, e, level.grid_tets);
  if (why.empty()) return Status::ok();
  return invalidData(path + ": level " + std::to_string(i) + " would not decode back to its mesh (" + why +
                     "), so the file was not written; this is a bug in gtn's encoder, please report it with the input");
}

// The bytes a level's chunks take, about (streams and merge tree; framing, tables and compression left
// out): what the writer compares to choose how to store a level, and to apply the storage bound.
uint64_t approxBytes(const EncodedInput& e) {
  uint64_t n = e.tree ? e.tree->size() : 0;
  for (const EncodedLevel& p : e.level.encoded) {
    n += p.boundary.size() + p.connectivity.size() + p.geometry.size();
    for (const auto& s : p.point_fields) n += s.size();
    for (const auto& s : p.cell_fields) n += s.size();
  }
  for (const auto& s : e.level.seam_streams) n += s.size();
  return n;
}

// Level i encoded so that it names the next level's vertices (whose encoding is `next`), with the part
// of its merge tree down to the next level.
StatusOr<EncodedInput> encodeChained(const std::vector<GtnLevelInput>& levels, size_t i, const TetMesh& mesh,
                                     const EncodedInput& next) {
  GTN_ASSIGN_OR_RETURN(std::vector<uint32_t> next_index, levels[i].next_index());
  EncodedInput out;
  GTN_ASSIGN_OR_RETURN(out.level, encodeChainedLevel(mesh, next_index, next.level.vertex_order));
  setLevelIndex(out.level, i, levels[i].merges);
  if (levels[i].merge_tree_prefix) {
    GTN_ASSIGN_OR_RETURN(out.tree, levels[i].merge_tree_prefix(out.level.vertex_order,
                                                               levels[i + 1].merges - levels[i].merges, next_index));
  } else if (levels[i].merge_tree) {
    GTN_ASSIGN_OR_RETURN(out.tree, levels[i].merge_tree(out.level.vertex_order));
  }
  return out;
}

// Whether level i decodes back to its mesh, given the next level's mesh and encoding when it names its
// vertices (checkDecodesBack's check for such a level).
Status checkChainedDecodesBack(const std::string& path, const GtnLevelInput& level, const TetMesh& mesh, size_t i,
                               const EncodedInput& e, const TetMesh* next_mesh, const EncodedInput* next,
                               const GtnWriteOptions& options) {
  if (e.level.base == 0) return checkDecodesBack(path, level, mesh, i, e.level, options);
  if (!options.verify) return Status::ok();
  if (level.check_mesh) GTN_RETURN_IF_ERROR(level.check_mesh(mesh));
  const ChainSeams seams = chainSeamsOf(*next_mesh, next->level.vertex_order);
  const SeamValues view = seams.view();
  const std::string why = losslessMismatch(mesh, e.level.encoded[0], &view);
  if (why.empty()) return Status::ok();
  return invalidData(path + ": level " + std::to_string(i) + " would not decode back to its mesh (" + why +
                     "), so the file was not written; this is a bug in gtn's encoder, please report it with the input");
}

}  // namespace

Status writeGtnFile(const std::string& path, const std::vector<GtnLevelInput>& levels, const GtnWriteOptions& options) {
  if (levels.empty()) return usageError(path + ": no level to write");
  if (options.piece_tets < kMinPieceTets)
    return usageError(path + ": a piece holds at most " + std::to_string(options.piece_tets) +
                      " tetrahedra; the bound must be at least " + std::to_string(kMinPieceTets));
  for (size_t i = 0; i < levels.size(); ++i) {
    if (!levels[i].mesh && !levels[i].make_mesh)
      return usageError(path + ": level " + std::to_string(i) + " has no mesh");
    if (levels[i].grid_tets && (!levels[i].encoded || !levels[i].encoded->isGrid() || levels[i].next_index))
      return usageError(path + ": level " + std::to_string(i) +
                        " has its tetrahedra apart, but no structured encoding, or may name the next level's vertices");
  }
  // With a storage bound every level is encoded first (the encoded streams are small); without one,
  // one level is encoded at a time, so the encoder's memory is released before the next level.
  const bool bounded = options.level_storage_limit > 0.0 && levels.size() > 1;
  // Progress: the share of all levels' tetrahedra before level i (level 0 takes most of the time).
  std::vector<double> before(levels.size() + 1, 0.0);
  for (size_t i = 0; i < levels.size(); ++i)
    before[i + 1] = before[i] + static_cast<double>(levels[i].grid_tets ? levels[i].grid_tets->size()
                                                    : levels[i].mesh    ? levels[i].mesh->numTets()
                                                                        : levels[i].expected_tets);
  auto progress = [&](const char* what, size_t i) {
    reportProgress(
        options.progress,
        std::string(what) + " level " + std::to_string(i) + " (" + std::to_string(levels.size()) + " levels)",
        before.back() > 0 ? before[i] / before.back() : 0.0);
  };
  // Each level's mesh, made (make_mesh) when the level is first reached.
  std::vector<const TetMesh*> meshes(levels.size(), nullptr);
  auto meshOf = [&](size_t i) -> StatusOr<const TetMesh*> {
    if (!meshes[i]) {
      if (levels[i].mesh) {
        meshes[i] = levels[i].mesh;
      } else {
        GTN_ASSIGN_OR_RETURN(meshes[i], levels[i].make_mesh());
        if (!meshes[i]) return usageError(path + ": level " + std::to_string(i) + " has no mesh");
      }
    }
    return meshes[i];
  };
  std::vector<EncodedInput> encoded;
  size_t count = levels.size();
  const bool chained =
      options.chain_levels && levels.size() > 1 &&
      std::any_of(levels.begin(), levels.end() - 1, [](const GtnLevelInput& l) { return bool(l.next_index); });
  if (chained) {
    // Levels that name the next level's vertices: every level's mesh is made (finest first, each from
    // the one before), then the levels are encoded coarsest first, each level choosing between naming
    // the next level's vertices (with the part of its merge tree down to that level) and storing all
    // its own (with the rest of the tree), by bytes.
    for (size_t i = 0; i < levels.size(); ++i) GTN_RETURN_IF_ERROR(meshOf(i).status());
    encoded.resize(levels.size());
    uint64_t alone0 = 0;  // level 0 stored alone: the unit of the storage bound
    auto canChain = [&](size_t i) {
      return i + 1 < count && levels[i].next_index && meshes[i]->numTets() <= options.piece_tets;
    };
    // Level 0 stored alone needs no other level (its merge tree, the whole one, is most of its work):
    // it is encoded on another thread while the coarser levels are, coarsest first. The meshes are all
    // made, so the levels' inputs are only read from here on.
    std::optional<StatusOr<EncodedInput>> level0_alone;
    // The levels' checks (verify) start as soon as the first pass down has made a level final: a
    // level i > 0 when it is encoded (the level it names, i + 1, is final before it), and a level 0
    // stored as a grid, which is kept whatever the other levels' bytes (encodeDown), when its
    // encoding alone is done, beside the coarser levels' encoding. They are tasks of `ahead`, run by
    // the thread that waits for level 0's encoding where no other thread takes them. early[i]: level
    // i's check, made while encoded[i] (and encoded[i + 1]) are the levels it checked; the bound
    // (below) may encode levels again, and then every level is checked again.
    std::vector<std::optional<Status>> early(count);
    std::optional<Status> level0_grid_check;
    bool first_pass = true;
    auto checkLevel = [&](size_t i) {
      if (options.verify) progress("verify", i);
      return checkChainedDecodesBack(path, levels[i], *meshes[i], i, encoded[i],
                                     i + 1 < count ? meshes[i + 1] : nullptr, i + 1 < count ? &encoded[i + 1] : nullptr,
                                     options);
    };
    // Waited for on every return from here, before what its tasks use is gone.
    tbb::task_group ahead;
    const WaitOnExit join_ahead{ahead};
    // A grid level 0 given encoded is checked from the start, as a task of its own beside its merge
    // tree's encoding (a long one thread's work on a large grid), by the first thread free for it.
    // The task holds a reference to the encoding, so that encodeInput copies it rather than move
    // from it while the check reads it.
    const std::shared_ptr<PiecedLevel>& given0 = levels[0].encoded;
    const bool check0_early = count > 1 && options.verify && given0 && !given0->encoded.empty() && given0->isGrid();
    if (check0_early)
      ahead.run(
          [&, held = given0] { level0_grid_check = checkDecodesBack(path, levels[0], *meshes[0], 0, *held, options); });
    if (count > 1)
      ahead.run([&] {
        level0_alone = encodeInput(levels, 0, *meshes[0], options);
        if (!check0_early && options.verify && level0_alone->isOk() && (*level0_alone)->level.isGrid())
          level0_grid_check = checkDecodesBack(path, levels[0], *meshes[0], 0, (*level0_alone)->level, options);
      });
    auto encodeAlone = [&](size_t i) -> StatusOr<EncodedInput> {
      if (i != 0) return encodeInput(levels, i, *meshes[i], options);
      ahead.wait();
      if (!level0_alone) return encodeInput(levels, 0, *meshes[0], options);  // a later pass down
      StatusOr<EncodedInput> taken = std::move(*level0_alone);
      level0_alone.reset();
      return taken;
    };
    auto encodeDown = [&](size_t top) -> Status {  // levels top, top - 1, ..., 0
      for (size_t i = top + 1; i-- > 0;) {
        progress("encode", i);
        std::optional<EncodedInput> best;
        if (canChain(i)) {
          auto c = encodeChained(levels, i, *meshes[i], encoded[i + 1]);
          if (!c.isOk()) return c.status();
          best = std::move(c).value();
        }
        // Level 0 (often given encoded alone already, and the bound's unit) and grids (often smaller
        // as a structured piece) are also encoded storing all their vertices; other levels always
        // take fewer bytes naming the next level's.
        if (!best || i == 0 || !meshes[i]->blocks.empty()) {
          auto a = encodeAlone(i);
          if (!a.isOk()) return a.status();
          if (i == 0) alone0 = approxBytes(*a);
          // A structured piece is kept whatever the bytes: it decodes at memory speed, alone, where a
          // level naming the next one decodes with the level codec after every coarser level.
          const bool grid = a->level.isGrid();
          if (!best || grid || approxBytes(*a) < approxBytes(*best)) best = std::move(a).value();
        }
        encoded[i] = std::move(*best);
        if (first_pass && options.verify) {
          if (i > 0) ahead.run([&, i] { early[i] = checkLevel(i); });
          else if (level0_grid_check && encoded[0].level.isGrid()) early[0] = std::move(level0_grid_check);
        }
      }
      return Status::ok();
    };
    GTN_RETURN_IF_ERROR(encodeDown(count - 1));
    first_pass = false;
    ahead.wait();
    if (bounded) {
      auto total = [&] {
        uint64_t t = 0;
        for (size_t i = 0; i < count; ++i) t += approxBytes(encoded[i]);
        return t;
      };
      // Past the bound, the coarsest level is left out and the new coarsest stores all its vertices.
      while (count > 1 && static_cast<double>(total()) > options.level_storage_limit * static_cast<double>(alone0)) {
        --count;
        early.assign(count, std::nullopt);
        const std::vector<uint32_t> order = encoded[count - 1].level.vertex_order;
        GTN_ASSIGN_OR_RETURN(encoded[count - 1], encodeInput(levels, count - 1, *meshes[count - 1], options));
        if (encoded[count - 1].level.vertex_order != order && count > 1) GTN_RETURN_IF_ERROR(encodeDown(count - 2));
      }
      encoded.resize(count);
    }
    // The levels not checked yet, in parallel; the first failure in level order is returned. Each
    // check reports its stage as it starts (ProgressFn is thread-safe).
    tbb::parallel_for(size_t{0}, count, [&](size_t i) {
      if (!early[i]) early[i] = checkLevel(i);
    });
    for (const std::optional<Status>& c : early) GTN_RETURN_IF_ERROR(*c);
  } else if (bounded) {
    // Each level is checked on another thread while the next one is encoded: one encoder's memory
    // at a time, and the check's time hidden behind the encoding. The bytes each level takes in the
    // file are measured as it is encoded, by writing it to a counter with the same options: the
    // first level that passes the bound ends the encoding (neither it nor a coarser one is kept, so
    // none of them is encoded or checked). Failures are reported in level order.
    encoded.reserve(levels.size());  // the checks read encoded[i] while later levels are added
    std::vector<Status> checks(levels.size());
    tbb::task_group checking;
    Status failed;
    GtnStreamWriter counter([](std::span<const uint8_t>) { return Status::ok(); }, options);
    uint64_t level0 = 0, total = 0;
    count = 0;
    for (size_t i = 0; i < levels.size(); ++i) {
      auto mesh = meshOf(i);
      if (!mesh.isOk()) {
        failed = mesh.status();
        break;
      }
      progress(options.verify ? "encode and verify" : "encode", i);
      auto e = encodeInput(levels, i, **mesh, options);
      if (!e.isOk()) {
        failed = e.status();
        break;
      }
      if (i == 0) failed = counter.begin(e->level.header, levels.size());
      const uint64_t offset = counter.offset();
      if (failed.isOk()) failed = counter.addLevel(e->level, levels[i].ratio, e->tree);
      if (!failed.isOk()) {
        failed = namedByOutput(path, failed);
        break;
      }
      const uint64_t bytes = counter.offset() - offset;
      if (i == 0) level0 = bytes;
      total += bytes;
      if (i > 0 && static_cast<double>(total) > options.level_storage_limit * static_cast<double>(level0)) break;
      encoded.push_back(std::move(e).value());
      ++count;
      checking.run([&, i] { checks[i] = checkDecodesBack(path, levels[i], *meshes[i], i, encoded[i].level, options); });
    }
    checking.wait();
    GTN_RETURN_IF_ERROR(failed);
    for (size_t i = 0; i < count; ++i) GTN_RETURN_IF_ERROR(checks[i]);
  }
  return writeFileAtomically(path, [&](std::FILE* f) -> Status {
    GtnStreamWriter w(fileOutput(f), options);
    for (size_t i = 0; i < count; ++i) {
      EncodedInput one;
      if (!bounded && !chained) {
        GTN_ASSIGN_OR_RETURN(const TetMesh* mesh, meshOf(i));
        progress("encode", i);
        auto e = encodeInput(levels, i, *mesh, options);
        if (!e.isOk()) return e.status();
        one = std::move(e).value();
        if (options.verify) progress("verify", i);
        GTN_RETURN_IF_ERROR(checkDecodesBack(path, levels[i], *mesh, i, one.level, options));
      }
      const EncodedInput& e = bounded || chained ? encoded[i] : one;
      if (i == 0) GTN_RETURN_IF_ERROR(namedByOutput(path, w.begin(e.level.header, count)));
      GTN_RETURN_IF_ERROR(namedByOutput(path, w.addLevel(e.level, levels[i].ratio, e.tree)));
    }
    return namedByOutput(path, w.finish());
  });
}

}  // namespace gtn
