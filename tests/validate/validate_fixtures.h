// Helpers for the validator's tests: valid .gtn files made with the project's own writer, and a
// test-only re-writer that rebuilds a file chunk by chunk (fresh checksums, directory and trailer)
// after a mutation, to make files the normal writer cannot produce.
#pragma once

#include <gtest/gtest.h>

#include <functional>
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
struct RewriteChunk {
  ChunkTag tag;
  int level = -1;
  Bytes payload;
  bool ancillary = false;
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
  chunks.push_back({kTagFileHeader, -1, encodeFileHeader(reader.file().header), false});
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
    chunks.push_back({kTagLevelHeader, level, encodeLevelRecord(rec), false});
    if (li.pieces.size() > 1) {
      Bytes seam;
      EXPECT_TRUE(reader.readSeamTable(i, &seam).isOk());
      chunks.push_back({kTagSeam, level, seam, false});
    }
    for (size_t p = 0; p < li.pieces.size(); ++p) {
      StatusOr<GtnLevelStreams> s = reader.readPieceStreams(i, p);
      EXPECT_TRUE(s.isOk());
      chunks.push_back({kTagBoundary, level, s->boundary, false});
      chunks.push_back({kTagConnectivity, level, s->connectivity, false});
      chunks.push_back({kTagGeometry, level, s->geometry, false});
      for (const auto& f : s->point_fields) chunks.push_back({kTagPointField, level, f, false});
      for (const auto& f : s->cell_fields) chunks.push_back({kTagCellField, level, f, false});
    }
    auto mt = reader.mergeTreePayload(i);
    EXPECT_TRUE(mt.isOk());
    if (mt->has_value()) chunks.push_back({kTagMergeTree, level, **mt, false});
  }
  mutate(chunks);
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
