// Damaged chunks: every command that opens a .gtn file checks the checksum of every chunk and warns,
// naming the chunk, where it does not need it (level 0 of a file whose merge tree or coarse level is
// damaged), and fails where it does. Files are made from a generated mesh; one byte is flipped in
// each chunk in turn.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "format/gtn_file.h"
#include "format/gtn_reader.h"
#include "mesh/mesh_stats.h"
#include "test_util.h"

namespace gtn {
namespace {

struct Chunk {
  GtnChunkInfo info;
  int level = -1;
};

// Every chunk of a file, from a full scan.
std::vector<Chunk> chunksOf(const std::string& path) {
  auto r = GtnReader::open(path);
  EXPECT_TRUE(r.isOk()) << r.status().message();
  std::vector<Chunk> out;
  if (!r.isOk()) return out;
  for (const GtnChunkInfo& c : (*r)->file().chunks) out.push_back({c, -1});
  for (size_t i = 0; i < (*r)->levels(); ++i)
    for (const GtnChunkInfo& c : (*r)->level(i).chunks) out.push_back({c, static_cast<int>(i)});
  return out;
}

// The file with one byte of the chunk's stored payload flipped (of its checksum when it has none).
std::string flipped(const std::string& bytes, const GtnChunkInfo& c) {
  std::string out = bytes;
  const uint64_t header = c.bytes - c.stored_bytes - kChunkChecksumSize;
  const uint64_t at = c.stored_bytes > 0 ? c.offset + header + c.stored_bytes / 2 : c.offset + c.bytes - 1;
  out[at] = static_cast<char>(out[at] ^ 0x20);
  return out;
}

std::string describe(const Chunk& c) {
  return c.info.tag.str() + " (" + c.info.section + ", level " + std::to_string(c.level) + ")";
}

class GtnDamage : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = test::tempDir("gtn-damage");
    test::writeFile(dir_ + "/grid.vtk", test::shearedHexGridVtk(7, /*mirrored=*/false, /*block_field=*/true));
    const test::RunResult r = test::runGtn("convert " + dir_ + "/grid.vtk -o " + dir_ + "/grid.gtn --levels 1");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    bytes_ = test::readFile(dir_ + "/grid.gtn");
  }
  static std::string dir_, bytes_;
};
std::string GtnDamage::dir_, GtnDamage::bytes_;

TEST_F(GtnDamage, TheTestFileHoldsEveryChunkKind) {
  std::vector<std::string> tags;
  for (const Chunk& c : chunksOf(dir_ + "/grid.gtn")) tags.push_back(c.info.tag.str() + std::to_string(c.level));
  for (const char* want : {"GHDR-1", "LHDR0", "PIEC0", "MTRE0", "LHDR1", "PIEC1", "MTRE1", "DIRC-1", "GEND-1"})
    EXPECT_NE(std::find(tags.begin(), tags.end(), want), tags.end()) << want;
}

// Undamaged: no command says anything about checksums.
TEST_F(GtnDamage, AnIntactFileGivesNoWarning) {
  const test::RunResult e = test::runGtn("export " + dir_ + "/grid.gtn -o " + dir_ + "/intact.vtu");
  ASSERT_EQ(e.exit_code, 0) << e.err;
  EXPECT_EQ(e.err, "");
}

// One byte flipped in each chunk in turn: export, render and convert of level 0 go on with a warning
// that names the chunk where they do not need it, and fail where they do (level 0's content and that of
// the levels whose vertices it names); info and validate fail.
TEST_F(GtnDamage, EveryCommandChecksEveryChunk) {
  const std::vector<Chunk> chunks = chunksOf(dir_ + "/grid.gtn");
  ASSERT_GE(chunks.size(), 9u);
  // Level 0 needs the content of the levels whose vertices it names (spec 7.7): level 1 here.
  std::vector<bool> level0_needs;
  {
    auto r = GtnReader::open(dir_ + "/grid.gtn");
    ASSERT_TRUE(r.isOk()) << r.status().message();
    bool named = true;
    for (size_t i = 0; i < (*r)->levels(); ++i) {
      level0_needs.push_back(named);
      named = named && (*r)->level(i).base != 0;
    }
    ASSERT_TRUE(level0_needs.size() > 1 && level0_needs[1]) << "level 0 names level 1's vertices";
  }
  int index = 0;
  for (const Chunk& c : chunks) {
    SCOPED_TRACE(describe(c));
    const std::string path = dir_ + "/d" + std::to_string(index++) + ".gtn";
    test::writeFile(path, flipped(bytes_, c.info));
    const std::string tag = std::string("'").append(c.info.tag.str()).append("'");
    // Content chunks of level 0 (other than its merge tree) are what level 0 needs; headers, the
    // directory and the trailer are read at open.
    const bool structural = c.info.tag == kTagFileHeader || c.info.tag == kTagLevelHeader ||
                            c.info.tag == kTagDirectory || c.info.tag == kTagEnd;
    const bool needed = structural || (c.level >= 0 && static_cast<size_t>(c.level) < level0_needs.size() &&
                                       level0_needs[c.level] && c.info.tag != kTagMergeTree);
    const std::vector<std::pair<std::string, std::string>> commands = {
        {"export", "export " + path + " -o " + path + ".vtu"},
        {"export from standard input", "export - -o " + path + ".stdin.vtu < " + path},
        {"render", "render " + path + " --level 0 --size 24x24 -o " + path + ".png"},
        {"convert", "convert " + path + " -o " + path + ".vtk"},
    };
    for (const auto& [name, args] : commands) {
      SCOPED_TRACE(name);
      const test::RunResult r = test::runGtn(args);
      EXPECT_NE(r.err.find("checksum mismatch in chunk " + tag), std::string::npos) << r.err;
      if (needed) {
        EXPECT_NE(r.exit_code, 0) << r.err;
        EXPECT_NE(r.err.find("gtn: error:"), std::string::npos) << r.err;
        // Said once, by the error, not also by a warning before it.
        const size_t first = r.err.find("checksum mismatch in chunk " + tag);
        EXPECT_EQ(r.err.find("checksum mismatch in chunk " + tag, first + 1), std::string::npos) << r.err;
      } else {
        EXPECT_EQ(r.exit_code, 0) << r.err;
        EXPECT_NE(r.err.find("gtn: warning: "), std::string::npos) << r.err;
        EXPECT_NE(r.err.find("level " + std::to_string(c.level) + ", " + c.info.section), std::string::npos) << r.err;
        EXPECT_EQ(r.err.find("gtn: error:"), std::string::npos) << r.err;
      }
    }
    const test::RunResult info = test::runGtn("info " + path);
    EXPECT_NE(info.exit_code, 0);
    EXPECT_NE(info.err.find("checksum mismatch in chunk " + tag), std::string::npos) << info.err;
    const test::RunResult v = test::runGtn("validate " + path);
    EXPECT_EQ(v.exit_code, 1) << v.out << v.err;
    EXPECT_NE(v.out.find("CHECKSUM_MISMATCH"), std::string::npos) << v.out;
  }
}

// The format layer: damagedChunks names exactly the damaged chunk, whether the file was opened through
// its directory or scanned (a file without a directory); reading that chunk fails, the others read.
TEST_F(GtnDamage, DamagedChunksNamesTheChunkBothWaysOfOpening) {
  const std::string no_dir = dir_ + "/nodir.gtn";
  {
    auto r = GtnReader::open(dir_ + "/grid.gtn");
    ASSERT_TRUE(r.isOk());
    TetMeshBuilder b;
    ASSERT_TRUE((*r)->decodeLevel(0, b).isOk());
    TetMesh mesh = std::move(b.mesh());
    GtnWriteOptions wo;
    wo.directory = false;
    GtnLevelInput l0;
    l0.mesh = &mesh;
    l0.merge_tree = [](const std::vector<uint32_t>&) -> StatusOr<std::vector<uint8_t>> {
      return std::vector<uint8_t>(64, 7);  // an ancillary-free stand-in payload: never decoded here
    };
    ASSERT_TRUE(writeGtnFile(no_dir, {l0}, wo).isOk());
  }
  for (const std::string& file : {dir_ + "/grid.gtn", no_dir}) {
    SCOPED_TRACE(file);
    const std::string bytes = test::readFile(file);
    for (const Chunk& c : chunksOf(file)) {
      if (c.info.tag != kTagMergeTree || c.level != 0) continue;
      const std::string damaged = flipped(bytes, c.info);
      GtnOpenOptions partial;
      partial.verify = false;
      auto r = GtnReader::openMemory(damaged, "m.gtn", partial);
      ASSERT_TRUE(r.isOk()) << r.status().message();
      EXPECT_EQ((*r)->openedByDirectory(), file != no_dir);
      auto d = (*r)->damagedChunks();
      ASSERT_TRUE(d.isOk()) << d.status().message();
      ASSERT_EQ(d->size(), 1u);
      EXPECT_EQ((*d)[0].chunk.offset, c.info.offset);
      EXPECT_EQ((*d)[0].level, 0);
      EXPECT_NE((*d)[0].message.find("m.gtn: byte offset " + std::to_string(c.info.offset) +
                                     ": checksum mismatch in chunk 'MTRE' (level 0, merge_tree"),
                std::string::npos)
          << (*d)[0].message;
      TetMeshBuilder b;
      EXPECT_TRUE((*r)->decodeLevel(0, b).isOk());
      auto tree = (*r)->mergeTreePayload(0);
      ASSERT_FALSE(tree.isOk());
      EXPECT_NE(tree.status().message().find("checksum mismatch"), std::string::npos);
      // A full verification still rejects the file at open.
      EXPECT_FALSE(GtnReader::openMemory(damaged, "m.gtn").isOk());
      // openGtnChecked warns once, with the same message.
      std::vector<std::string> warnings;
      const std::string path = dir_ + "/checked.gtn";
      test::writeFile(path, damaged);
      auto checked = openGtnChecked(path, partial, [&](const std::string& w) { warnings.push_back(w); });
      ASSERT_TRUE(checked.isOk());
      ASSERT_EQ(warnings.size(), 1u);
      EXPECT_NE(warnings[0].find("checksum mismatch in chunk 'MTRE'"), std::string::npos) << warnings[0];
    }
    auto intact = GtnReader::openMemory(bytes, "m.gtn", GtnOpenOptions{false});
    ASSERT_TRUE(intact.isOk());
    auto none = (*intact)->damagedChunks();
    ASSERT_TRUE(none.isOk());
    EXPECT_TRUE(none->empty());
  }
}

}  // namespace
}  // namespace gtn
