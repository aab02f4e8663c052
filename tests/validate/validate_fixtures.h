// Helpers for the validator's tests: valid .gtn files made with the project's own writer, and a
// test-only re-writer that rebuilds a file chunk by chunk (fresh checksums, directory and trailer)
// after a mutation, to make files the normal writer cannot produce.
#pragma once

#include <gtest/gtest.h>

#include <functional>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "codec/merge_tree_coder.h"
#include "format/file_io.h"
#include "format/gtn_chunk.h"
#include "format/gtn_file.h"
#include "format/gtn_reader.h"
#include "format/gtn_records.h"
#include "simplify/levels.h"
#include "simplify/ranking.h"
#include "simplify/simplify_test_util.h"
#include "test_util.h"
#include "validate/validator.h"

namespace gtn::test {

using Bytes = std::vector<uint8_t>;

inline Bytes readBytes(const std::string& path) {
  const std::string s = readFile(path);
  return Bytes(s.begin(), s.end());
}
inline void writeBytes(const std::string& path, const Bytes& b) { writeFile(path, std::string(b.begin(), b.end())); }

// Writes `mesh` as .gtn: with `levels` >= 0, ranks its merges and stores that many mip levels (with
// merge trees); with levels < 0, level 0 only and no merge tree.
inline void writeValidGtn(const std::string& path, const TetMesh& mesh, int levels, bool zstd = true) {
  GtnWriteOptions wo;
  wo.tool_version = "validate-test";
  wo.zstd = zstd;
  if (levels < 0) {
    GtnLevelInput in;
    in.mesh = &mesh;
    ASSERT_TRUE(writeGtnFile(path, {in}, wo).isOk());
    return;
  }
  RankingOptions ro;
  StatusOr<MergeTree> tree = rankMerges(mesh, ro, nullptr);
  ASSERT_TRUE(tree.isOk()) << tree.status().message();
  LevelOptions lo;
  lo.levels = levels;
  StatusOr<MipLevels> mips = buildMipLevels(mesh, *tree, lo);
  ASSERT_TRUE(mips.isOk()) << mips.status().message();
  const Status st = writeGtnFile(path, mips->inputs(mesh), wo);
  ASSERT_TRUE(st.isOk()) << st.message();
}

// One chunk of a file being rebuilt: its tag and (decompressed) payload; `level` is -1 outside levels.
// An LHDR keeps its record, a PIEC its codec streams: both are encoded when the file is assembled,
// the LHDR with the sizes of its level's PIEC streams as they are then.
struct RewriteChunk {
  ChunkTag tag;
  int level = -1;
  Bytes payload;
  bool ancillary = false;
  std::vector<Bytes> streams;            // PIEC: BNDY, CONN, GEOM, PFLD..., CFLD...
  std::optional<GtnLevelRecord> record;  // LHDR
};

// Rebuilds the file at `path` from its parsed content: prefix, GHDR, each level's chunks, DIRC and
// GEND, calling `mutate` on the list of chunks first (it may edit, drop or insert chunks). Chunks are
// stored raw (no zstd) and every checksum, the directory and the trailer are recomputed.
inline Bytes rewriteGtn(const std::string& path, const std::function<void(std::vector<RewriteChunk>&)>& mutate) {
  StatusOr<std::unique_ptr<GtnReader>> r = GtnReader::open(path);
  EXPECT_TRUE(r.isOk()) << r.status().message();
  if (!r.isOk()) return {};
  GtnReader& reader = *r.value();
  std::vector<RewriteChunk> chunks;
  chunks.push_back({kTagFileHeader, -1, encodeFileHeader(reader.file().header), false, {}, {}});
  for (size_t i = 0; i < reader.levels(); ++i) {
    const GtnLevelInfo& li = reader.level(i);
    GtnLevelRecord rec;
    rec.level = i;
    rec.merges = li.header.merges;
    rec.ratio = li.ratio;
    rec.points = li.header.points;
    rec.tets = li.header.tets;
    rec.boundary_triangles = li.header.boundary_triangles;
    for (int k = 0; k < 3; ++k) {
      rec.bbox_min[k] = li.header.bbox_min[k];
      rec.bbox_max[k] = li.header.bbox_max[k];
    }
    rec.pieces = li.pieces;
    rec.base = li.base;
    const int level = static_cast<int>(i);
    chunks.push_back({kTagLevelHeader, level, {}, false, {}, rec});
    if (li.pieces.size() > 1) {
      Bytes seam;
      EXPECT_TRUE(reader.readSeamTable(i, &seam).isOk());
      chunks.push_back({kTagSeam, level, seam, false, {}, {}});
    }
    for (size_t p = 0; p < li.pieces.size(); ++p) {
      StatusOr<GtnLevelStreams> s = reader.readPieceStreams(i, p);
      EXPECT_TRUE(s.isOk());
      if (li.pieces[p].kind == kPieceStructured) {
        chunks.push_back({kTagGrid, level, s->connectivity, false, {}, {}});
        continue;
      }
      std::vector<Bytes> streams = {s->boundary, s->connectivity, s->geometry};
      streams.insert(streams.end(), s->point_fields.begin(), s->point_fields.end());
      streams.insert(streams.end(), s->cell_fields.begin(), s->cell_fields.end());
      chunks.push_back({kTagPiece, level, {}, false, std::move(streams), {}});
    }
    auto mt = reader.mergeTreePayload(i);
    EXPECT_TRUE(mt.isOk());
    if (mt->has_value()) chunks.push_back({kTagMergeTree, level, **mt, false, {}, {}});
  }
  mutate(chunks);
  // PIEC payloads from their streams, and the LHDRs with those streams' sizes.
  std::vector<std::vector<std::vector<uint64_t>>> sizes(reader.levels());
  for (RewriteChunk& c : chunks) {
    if (c.tag != kTagPiece || c.streams.empty()) continue;
    c.payload.clear();
    std::vector<uint64_t> piece;
    for (const Bytes& b : c.streams) {
      c.payload.insert(c.payload.end(), b.begin(), b.end());
      piece.push_back(b.size());
    }
    if (c.level >= 0 && static_cast<size_t>(c.level) < sizes.size()) sizes[c.level].push_back(std::move(piece));
  }
  LevelRecordContext context = levelRecordContext(reader.file().header);
  for (RewriteChunk& c : chunks) {
    if (c.tag != kTagLevelHeader || !c.record) continue;
    GtnLevelRecord& rec = *c.record;
    rec.streams.assign(rec.pieces.size(), {});
    size_t k = 0;
    for (size_t p = 0; p < rec.pieces.size(); ++p)
      if (rec.pieces[p].kind == kPieceUnstructured && k < sizes[c.level].size()) rec.streams[p] = sizes[c.level][k++];
    c.payload = encodeLevelRecord(rec, context);
    context = nextLevelRecordContext(context, rec);
  }
  Bytes out;
  const auto prefix = encodeGtnPrefix();
  out.insert(out.end(), prefix.begin(), prefix.end());
  GtnDirectory dir(reader.levels());
  for (const RewriteChunk& c : chunks) {
    const uint64_t offset = out.size();
    appendGtnChunk(out, c.tag, c.payload, c.ancillary, false, 0);
    if (c.level >= 0 && static_cast<size_t>(c.level) < dir.size())
      dir[c.level].push_back({c.tag, offset, out.size() - offset});
  }
  const uint64_t dir_offset = out.size();
  appendGtnChunk(out, kTagDirectory, encodeDirectory(dir), false, false, 0);
  GtnTrailer t;
  t.directory_offset = dir_offset;
  t.directory_size = out.size() - dir_offset;
  appendGtnChunk(out, kTagEnd, encodeTrailer(t), false, false, 0);
  return out;
}

inline ValidationReport validateBytesForTest(const Bytes& bytes, const ValidateOptions& options = {}) {
  return validateGtnBytes(bytes, "test.gtn", options);
}

// The distinct codes of the report's messages with severity error.
inline std::set<std::string> errorCodeSet(const ValidationReport& r) {
  const std::vector<std::string> v = r.errorCodes();
  return std::set<std::string>(v.begin(), v.end());
}

}  // namespace gtn::test
