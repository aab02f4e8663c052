// The .gtn container on hand-made codec streams (independent of the codec): framing, checksums,
// order, truncation, trailing bytes, unknown chunks, versions, directory, determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <random>

#include "format/gtn_bytes.h"
#include "format/gtn_chunk.h"
#include "format/gtn_file.h"
#include "format/gtn_reader.h"
#include "format/gtn_records.h"
#include "test_util.h"

namespace gtn {
namespace {

std::vector<uint8_t> pattern(size_t n, uint32_t seed, bool compressible) {
  std::vector<uint8_t> v(n);
  std::mt19937 rng(seed);
  for (size_t i = 0; i < n; ++i) v[i] = compressible ? static_cast<uint8_t>((i / 7) % 5) : static_cast<uint8_t>(rng());
  return v;
}

// A level with streams of recognisable bytes: two point fields, one cell field.
EncodedLevel handMadeLevel(uint32_t level, uint64_t points, uint64_t tets) {
  EncodedLevel e;
  LevelHeader& h = e.header;
  h.level = level;
  h.merges = level * 10;
  h.points = points;
  h.tets = tets;
  h.boundary_triangles = 12;
  h.coord_type = ScalarType::kFloat32;
  h.point_fields = {{"density", 1, ScalarType::kFloat32}, {"velocity", 3, ScalarType::kFloat64}};
  h.cell_fields = {{"region", 1, ScalarType::kInt32}};
  h.bbox_min[0] = -1.5;
  h.bbox_max[2] = 2.25;
  h.metadata = {{"source", "hand made"}, {"units", "m"}};
  e.boundary = pattern(40, 1 + level, false);
  e.connectivity = pattern(300, 2 + level, true);  // zstd shrinks this one
  e.geometry = pattern(120, 3 + level, false);     // and not this one
  e.point_fields = {pattern(30, 4 + level, false), pattern(0, 5, false)};
  e.cell_fields = {pattern(9, 6 + level, false)};
  return e;
}

GtnWriteOptions opts(bool directory = true, bool zstd = true) {
  GtnWriteOptions o;
  o.tool_version = "test 1.0";
  o.command_line = "gtn convert in.vtk -o out.gtn";
  o.directory = directory;
  o.zstd = zstd;
  return o;
}

std::vector<uint8_t> twoLevelFile(bool directory = true) {
  const EncodedLevel l0 = handMadeLevel(0, 100, 400), l1 = handMadeLevel(1, 60, 200);
  std::vector<std::optional<std::vector<uint8_t>>> trees = {std::nullopt, pattern(50, 9, false)};
  auto bytes = assembleGtn({&l0, &l1}, opts(directory), {0.0, 0.4}, trees);
  EXPECT_TRUE(bytes.isOk()) << bytes.status().message();
  return bytes.value();
}

std::string writeTemp(const std::string& dir, const std::string& name, const std::vector<uint8_t>& b) {
  const std::string path = dir + "/" + name;
  test::writeFile(path, std::string(b.begin(), b.end()));
  return path;
}

Status memoryStatus(const std::vector<uint8_t>& b, bool verify = true) {
  GtnOpenOptions o;
  o.verify = verify;
  auto r = GtnReader::openMemory(std::string(b.begin(), b.end()), "mem.gtn", o);
  return r.isOk() ? Status::ok() : r.status();
}

Status openStatus(const std::string& path, bool verify = true) {
  GtnOpenOptions o;
  o.verify = verify;
  auto r = GtnReader::open(path, o);
  return r.isOk() ? Status::ok() : r.status();
}

TEST(GtnContainer, RoundTripStreamsHeadersAndSections) {
  const std::string dir = test::tempDir("container-roundtrip");
  const std::vector<uint8_t> bytes = twoLevelFile();
  const std::string path = writeTemp(dir, "two.gtn", bytes);
  for (bool verify : {true, false}) {
    GtnOpenOptions o;
    o.verify = verify;
    auto opened = GtnReader::open(path, o);
    ASSERT_TRUE(opened.isOk()) << opened.status().message();
    GtnReader& r = **opened;
    EXPECT_EQ(r.openedByDirectory(), !verify);
    EXPECT_EQ(r.file().major, 2);
    EXPECT_EQ(r.file().minor, 0);
    EXPECT_EQ(r.file().header.draft, kGtnDraftRevision);
    EXPECT_TRUE(r.file().has_directory);
    EXPECT_EQ(r.file().header.tool_version, "test 1.0");
    EXPECT_EQ(r.file().header.command_line, "gtn convert in.vtk -o out.gtn");
    ASSERT_EQ(r.levels(), 2u);
    for (uint32_t i = 0; i < 2; ++i) {
      const EncodedLevel want = handMadeLevel(i, i ? 60 : 100, i ? 200 : 400);
      const GtnLevelInfo& li = r.level(i);
      EXPECT_EQ(li.header.points, want.header.points);
      EXPECT_EQ(li.header.tets, want.header.tets);
      EXPECT_EQ(li.header.merges, want.header.merges);
      EXPECT_EQ(li.header.boundary_triangles, 12u);
      EXPECT_EQ(li.header.coord_type, ScalarType::kFloat32);
      ASSERT_EQ(li.header.point_fields.size(), 2u);
      EXPECT_EQ(li.header.point_fields[1].name, "velocity");
      EXPECT_EQ(li.header.point_fields[1].components, 3u);
      EXPECT_EQ(li.header.point_fields[1].type, ScalarType::kFloat64);
      EXPECT_EQ(li.header.cell_fields[0].type, ScalarType::kInt32);
      EXPECT_EQ(li.header.bbox_min[0], -1.5);
      EXPECT_EQ(li.header.bbox_max[2], 2.25);
      EXPECT_EQ(li.header.metadata, want.header.metadata);
      EXPECT_DOUBLE_EQ(li.ratio, i ? 0.4 : 0.0);
      EXPECT_EQ(li.has_merge_tree, i == 1);
      auto s = r.readLevelStreams(i);
      ASSERT_TRUE(s.isOk()) << s.status().message();
      EXPECT_EQ(s->boundary, want.boundary);
      EXPECT_EQ(s->connectivity, want.connectivity);
      EXPECT_EQ(s->geometry, want.geometry);
      EXPECT_EQ(s->point_fields, want.point_fields);
      EXPECT_EQ(s->cell_fields, want.cell_fields);
      auto mt = r.mergeTreePayload(i);
      ASSERT_TRUE(mt.isOk());
      EXPECT_EQ(mt->has_value(), i == 1);
      if (i == 1) {
        EXPECT_EQ(**mt, pattern(50, 9, false));
      }
    }
    // The pieces are stored compressed (their CONN streams shrink): a section of their own.
    uint64_t total = 0;
    bool saw_piece = false;
    for (const GtnSection& s : r.sections()) {
      total += s.bytes;
      saw_piece |= s.name == "piece";
    }
    EXPECT_EQ(total, bytes.size());
    EXPECT_TRUE(saw_piece);
    EXPECT_FALSE(r.readLevelStreams(2).isOk());
  }
  // Stored raw, a piece's bytes count in its streams' sections, and its framing apart.
  const EncodedLevel l0 = handMadeLevel(0, 100, 400);
  auto raw = assembleGtn({&l0}, opts(true, false));
  ASSERT_TRUE(raw.isOk());
  auto r = GtnReader::open(writeTemp(dir, "raw.gtn", raw.value()));
  ASSERT_TRUE(r.isOk()) << r.status().message();
  std::map<std::string, uint64_t> sections;
  uint64_t total = 0;
  for (const GtnSection& s : (*r)->sections()) {
    sections[s.name] = s.bytes;
    total += s.bytes;
  }
  EXPECT_EQ(total, raw->size());
  EXPECT_EQ(sections["connectivity"], l0.connectivity.size());
  EXPECT_EQ(sections["point_field:velocity"], l0.point_fields[1].size());
  EXPECT_EQ(sections["piece_framing"], kChunkFixedHeaderSize + kChunkChecksumSize);
  EXPECT_EQ(sections.count("piece"), 0u);
}

TEST(GtnContainer, ZstdOnlyWhereItHelps) {
  const std::string dir = test::tempDir("container-zstd");
  auto r = GtnReader::open(writeTemp(dir, "z.gtn", twoLevelFile()));
  ASSERT_TRUE(r.isOk());
  // Level 0's piece holds a compressible CONN stream; level 1's merge tree is random bytes.
  bool piece_zstd = false, tree_zstd = true;
  for (const GtnChunkInfo& c : (*r)->level(0).chunks)
    if (c.tag == kTagPiece) piece_zstd = c.zstd && c.stored_bytes < c.raw_bytes;
  for (const GtnChunkInfo& c : (*r)->level(1).chunks)
    if (c.tag == kTagMergeTree) tree_zstd = c.zstd;
  EXPECT_TRUE(piece_zstd);
  EXPECT_FALSE(tree_zstd);
  // Without zstd the file is bigger and reads back the same streams.
  const EncodedLevel l0 = handMadeLevel(0, 100, 400);
  auto raw = assembleGtn({&l0}, opts(true, false));
  auto packed = assembleGtn({&l0}, opts(true, true));
  ASSERT_TRUE(raw.isOk() && packed.isOk());
  EXPECT_GT(raw->size(), packed->size());
  auto rr = GtnReader::open(writeTemp(dir, "raw.gtn", raw.value()));
  ASSERT_TRUE(rr.isOk());
  EXPECT_EQ((*rr)->readLevelStreams(0)->connectivity, l0.connectivity);
}

TEST(GtnContainer, DeterministicOutput) {
  EXPECT_EQ(twoLevelFile(), twoLevelFile());
  EXPECT_EQ(twoLevelFile(false), twoLevelFile(false));
}

TEST(GtnContainer, WithoutDirectoryReadsTheSameAndRandomAccessFallsBack) {
  const std::string dir = test::tempDir("container-nodir");
  const std::vector<uint8_t> with = twoLevelFile(true), without = twoLevelFile(false);
  EXPECT_LT(without.size(), with.size());
  GtnOpenOptions fast;
  fast.verify = false;
  auto r = GtnReader::open(writeTemp(dir, "nodir.gtn", without), fast);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_FALSE((*r)->openedByDirectory());
  EXPECT_FALSE((*r)->file().has_directory);
  EXPECT_EQ((*r)->levels(), 2u);
  EXPECT_EQ((*r)->readLevelStreams(1)->geometry, handMadeLevel(1, 60, 200).geometry);
}

TEST(GtnContainer, EveryTruncatedPrefixFails) {
  const std::string dir = test::tempDir("container-trunc");
  const std::vector<uint8_t> bytes = twoLevelFile();
  const std::string path = "mem.gtn";
  for (size_t n = 0; n < bytes.size(); ++n) {
    for (bool verify : {true, false}) {
      const Status st = memoryStatus(std::vector<uint8_t>(bytes.begin(), bytes.begin() + n), verify);
      ASSERT_FALSE(st.isOk()) << "prefix of " << n << " bytes was accepted";
      EXPECT_NE(st.code(), StatusCode::kIo);
      if (n >= 8) {
        EXPECT_NE(st.message().find("byte offset"), std::string::npos) << st.message();
        EXPECT_NE(st.message().find(path), std::string::npos) << st.message();
      }
    }
  }
  // A cut at a chunk boundary names the missing end chunk; a cut inside one says truncated.
  const Status st = openStatus(writeTemp(dir, "t2.gtn", std::vector<uint8_t>(bytes.begin(), bytes.end() - 1)));
  EXPECT_NE(st.message().find("truncated"), std::string::npos) << st.message();
}

TEST(GtnContainer, TrailingBytesRejected) {
  const std::string dir = test::tempDir("container-trailing");
  std::vector<uint8_t> bytes = twoLevelFile();
  const size_t n = bytes.size();
  bytes.push_back(0);
  for (bool verify : {true, false}) {
    const Status st = openStatus(writeTemp(dir, "tr.gtn", bytes), verify);
    ASSERT_FALSE(st.isOk());
    EXPECT_EQ(st.code(), StatusCode::kInvalidData);
    EXPECT_NE(st.message().find("1 trailing bytes"), std::string::npos) << st.message();
    EXPECT_NE(st.message().find("byte offset " + std::to_string(n)), std::string::npos) << st.message();
  }
}

TEST(GtnContainer, EveryFlippedBitRejected) {
  const EncodedLevel l0 = handMadeLevel(0, 10, 20);
  auto made = assembleGtn({&l0}, opts(true));
  ASSERT_TRUE(made.isOk());
  const std::vector<uint8_t> bytes = made.value();
  ASSERT_LT(bytes.size(), 1200u);
  for (size_t bit = 0; bit < 8 * bytes.size(); ++bit) {
    std::vector<uint8_t> b = bytes;
    b[bit / 8] ^= static_cast<uint8_t>(1u << (bit % 8));
    const Status st = memoryStatus(b);
    ASSERT_FALSE(st.isOk()) << "flipped bit " << bit << " (byte " << bit / 8 << ") was accepted";
  }
}

TEST(GtnContainer, ChecksumMismatchNamesChunkAndOffset) {
  const std::string dir = test::tempDir("container-checksum");
  std::vector<uint8_t> bytes = twoLevelFile();
  auto r = GtnReader::open(writeTemp(dir, "ok.gtn", bytes));
  ASSERT_TRUE(r.isOk());
  const GtnChunkInfo geom = (*r)->level(1).chunks[1];
  ASSERT_EQ(geom.tag, kTagPiece);
  bytes[geom.offset + geom.bytes / 2] ^= 0x10;  // in the payload
  const std::string path = writeTemp(dir, "bad.gtn", bytes);
  const Status st = openStatus(path);
  EXPECT_EQ(st.code(), StatusCode::kInvalidData);
  EXPECT_NE(st.message().find("checksum mismatch in chunk 'PIEC'"), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("byte offset " + std::to_string(geom.offset)), std::string::npos) << st.message();
  // Opened through the directory, the damage shows when the level is read.
  GtnOpenOptions fast;
  fast.verify = false;
  auto lazy = GtnReader::open(path, fast);
  ASSERT_TRUE(lazy.isOk()) << lazy.status().message();
  EXPECT_TRUE((*lazy)->readLevelStreams(0).isOk());
  EXPECT_FALSE((*lazy)->readLevelStreams(1).isOk());
}

// Builds a one-level file without a directory and with an extra chunk after the GHDR and one inside
// the level.
std::vector<uint8_t> fileWithExtraChunk(ChunkTag tag, bool ancillary, bool directory) {
  const EncodedLevel l0 = handMadeLevel(0, 10, 20);
  std::vector<uint8_t> bytes;
  GtnStreamWriter w(
      [&](std::span<const uint8_t> b) {
        bytes.insert(bytes.end(), b.begin(), b.end());
        return Status::ok();
      },
      opts(directory));
  EXPECT_TRUE(w.begin(l0.header, 1).isOk());
  const std::vector<uint8_t> payload = pattern(33, 7, false);
  EXPECT_TRUE(w.addChunk(tag, payload, ancillary).isOk());
  EXPECT_TRUE(w.addLevel(l0, 0.0, std::nullopt).isOk());
  EXPECT_TRUE(w.addChunk(tag, payload, ancillary).isOk());
  EXPECT_TRUE(w.finish().isOk());
  return bytes;
}

TEST(GtnContainer, UnknownAncillaryChunkSkipped) {
  const std::string dir = test::tempDir("container-unknown");
  for (bool directory : {false, true}) {
    for (bool verify : {true, false}) {
      GtnOpenOptions o;
      o.verify = verify;
      auto r = GtnReader::open(writeTemp(dir, "u.gtn", fileWithExtraChunk(ChunkTag("zzXY"), true, directory)), o);
      ASSERT_TRUE(r.isOk()) << r.status().message();
      EXPECT_EQ((*r)->readLevelStreams(0)->geometry, handMadeLevel(0, 10, 20).geometry);
      uint64_t unknown = 0;
      for (const GtnSection& s : (*r)->sections())
        if (s.name == "unknown:zzXY") unknown = s.bytes;
      // Through the directory only the in-level one is listed.
      EXPECT_EQ((*r)->openedByDirectory(), directory && !verify);
      EXPECT_EQ(unknown, ((*r)->openedByDirectory() ? 1u : 2u) * (13 + 33 + 8)) << directory << verify;
    }
  }
}

TEST(GtnContainer, UnknownCriticalChunkRejected) {
  const std::string dir = test::tempDir("container-critical");
  const Status st = openStatus(writeTemp(dir, "c.gtn", fileWithExtraChunk(ChunkTag("ZZXY"), false, false)));
  EXPECT_EQ(st.code(), StatusCode::kInvalidData);
  EXPECT_NE(st.message().find("unknown critical chunk 'ZZXY'"), std::string::npos) << st.message();
}

TEST(GtnContainer, VersionsMajorRejectedMinorAccepted) {
  const std::string dir = test::tempDir("container-version");
  std::vector<uint8_t> bytes = twoLevelFile();
  const auto newer_major = encodeGtnPrefix(3, 0);
  std::copy(newer_major.begin(), newer_major.end(), bytes.begin());
  Status st = openStatus(writeTemp(dir, "v3.gtn", bytes));
  EXPECT_EQ(st.code(), StatusCode::kVersionTooNew);
  EXPECT_NE(st.message().find("format version 3.0 is newer"), std::string::npos) << st.message();
  // 1.x was never released: refused, naming its version.
  const auto older_major = encodeGtnPrefix(1, 0);
  std::copy(older_major.begin(), older_major.end(), bytes.begin());
  st = openStatus(writeTemp(dir, "v1.gtn", bytes));
  EXPECT_EQ(st.code(), StatusCode::kUnsupported);
  EXPECT_NE(st.message().find("format version 1.0 is not read"), std::string::npos) << st.message();
  const auto newer_minor = encodeGtnPrefix(2, 7);
  std::copy(newer_minor.begin(), newer_minor.end(), bytes.begin());
  auto r = GtnReader::open(writeTemp(dir, "v27.gtn", bytes));
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ((*r)->file().major, 2);
  EXPECT_EQ((*r)->file().minor, 7);
}

TEST(GtnContainer, MagicDiagnoses) {
  const std::string dir = test::tempDir("container-magic");
  std::vector<uint8_t> bytes = twoLevelFile();
  bytes[0] = 0x0E;
  Status st = openStatus(writeTemp(dir, "m1.gtn", bytes));
  EXPECT_EQ(st.code(), StatusCode::kNotOurFile);
  EXPECT_NE(st.message().find("high bit"), std::string::npos) << st.message();
  bytes[0] = 0x8E;
  bytes[4] = 0x0A;  // CR LF -> LF LF, as a text-mode conversion would do
  st = openStatus(writeTemp(dir, "m2.gtn", bytes));
  EXPECT_NE(st.message().find("text mode"), std::string::npos) << st.message();
  st = openStatus(writeTemp(dir, "m3.gtn", {'s', 'o', 'l', 'i', 'd', ' ', 'x', '\n'}));
  EXPECT_EQ(st.code(), StatusCode::kNotOurFile);
  EXPECT_NE(st.message().find("not a .gtn file"), std::string::npos) << st.message();
}

TEST(GtnContainer, ReservedFlagBitsRejected) {
  std::vector<uint8_t> chunk;
  appendGtnChunk(chunk, kTagPiece, pattern(20, 1, false), false, false, 1);
  chunk[4] |= 0x40;
  ChunkHeader h;
  size_t needed;
  const Status st = parseGtnChunkHeader(chunk, 16, chunk.size(), "x.gtn", &h, &needed);
  EXPECT_NE(st.message().find("reserved flag bits"), std::string::npos) << st.message();
}

TEST(GtnContainer, HugeDeclaredSizesFailBeforeAllocating) {
  // A GHDR claiming 2^60 payload bytes, and a zstd chunk claiming an absurd decompressed size.
  std::vector<uint8_t> chunk;
  appendGtnChunk(chunk, kTagFileHeader, pattern(20, 1, false), false, false, 1);
  for (int i = 0; i < 8; ++i) chunk[5 + i] = i == 7 ? 0x10 : 0;
  ChunkHeader h;
  size_t needed;
  Status st = parseGtnChunkHeader(chunk, 16, chunk.size(), "x.gtn", &h, &needed);
  EXPECT_NE(st.message().find("truncated"), std::string::npos) << st.message();
  std::vector<uint8_t> z;
  appendGtnChunk(z, kTagPiece, pattern(3000, 1, true), false, true, 3);
  ASSERT_EQ(z[4] & kChunkZstd, kChunkZstd);
  z[13 + 7] = 0x7F;  // raw_size high byte
  st = parseGtnChunkHeader(z, 16, z.size(), "x.gtn", &h, &needed);
  EXPECT_NE(st.message().find("beyond the format's bound"), std::string::npos) << st.message();
}

TEST(GtnContainer, VarintsAreStrict) {
  const uint8_t non_shortest[] = {0x81, 0x00};
  const uint8_t too_long[] = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x02};
  const uint8_t max[] = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x01};
  uint64_t v;
  EXPECT_FALSE(ByteReader(non_shortest, 0, "x").varint(&v, "n").isOk());
  EXPECT_FALSE(ByteReader(too_long, 0, "x").varint(&v, "n").isOk());
  ASSERT_TRUE(ByteReader(max, 0, "x").varint(&v, "n").isOk());
  EXPECT_EQ(v, UINT64_MAX);
  ByteWriter w;
  w.varint(UINT64_MAX);
  EXPECT_EQ(w.bytes(), std::vector<uint8_t>(std::begin(max), std::end(max)));
}

TEST(GtnContainer, ChunksOutOfOrderRejected) {
  // A level whose MTRE precedes its PIEC: built by swapping the two chunks of a directory-less file.
  const std::string dir = test::tempDir("container-order");
  const EncodedLevel l0 = handMadeLevel(0, 10, 20);
  auto made = assembleGtn({&l0}, opts(false), {0.0}, {pattern(50, 9, false)});
  ASSERT_TRUE(made.isOk());
  auto r = GtnReader::open(writeTemp(dir, "ok.gtn", made.value()));
  ASSERT_TRUE(r.isOk());
  const GtnChunkInfo bndy = (*r)->level(0).chunks[1], conn = (*r)->level(0).chunks[2];
  ASSERT_EQ(bndy.tag, kTagPiece);
  ASSERT_EQ(conn.tag, kTagMergeTree);
  const std::vector<uint8_t>& b = made.value();
  std::vector<uint8_t> swapped(b.begin(), b.begin() + bndy.offset);
  swapped.insert(swapped.end(), b.begin() + conn.offset, b.begin() + conn.offset + conn.bytes);
  swapped.insert(swapped.end(), b.begin() + bndy.offset, b.begin() + bndy.offset + bndy.bytes);
  swapped.insert(swapped.end(), b.begin() + conn.offset + conn.bytes, b.end());
  const Status st = openStatus(writeTemp(dir, "swapped.gtn", swapped));
  EXPECT_NE(st.message().find("out of order"), std::string::npos) << st.message();
}

TEST(GtnContainer, ReadsFromAPipe) {
  const std::string dir = test::tempDir("container-pipe");
  const std::string path = writeTemp(dir, "p.gtn", twoLevelFile());
  // A FIFO is not a regular file: the reader buffers it and scans front to back.
  const std::string fifo = dir + "/fifo";
  ASSERT_EQ(test::runShell("mkfifo " + fifo).exit_code, 0);
  const test::RunResult bg = test::runShell("(cat " + path + " > " + fifo + " &) ");
  ASSERT_EQ(bg.exit_code, 0);
  auto r = GtnReader::open(fifo);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ((*r)->levels(), 2u);
  EXPECT_EQ((*r)->readLevelStreams(1)->geometry, handMadeLevel(1, 60, 200).geometry);
}

// Re-frames the chunk at `offset` of `file` (a valid file) with a new payload and a valid checksum.
std::vector<uint8_t> reframe(const std::vector<uint8_t>& file, const GtnChunkInfo& c,
                             const std::vector<uint8_t>& payload) {
  std::vector<uint8_t> out(file.begin(), file.begin() + c.offset);
  appendGtnChunk(out, c.tag, payload, false, false, 1);
  out.insert(out.end(), file.begin() + c.offset + c.bytes, file.end());
  return out;
}

TEST(GtnContainer, MalformedPayloadsWithValidChecksumsFailCleanly) {
  // Checksums stop random damage early; this reaches the payload parsers behind them.
  const EncodedLevel l0 = handMadeLevel(0, 10, 20);
  auto made = assembleGtn({&l0}, opts(false, false));
  ASSERT_TRUE(made.isOk());
  const std::vector<uint8_t> file = made.value();
  auto r = GtnReader::openMemory(std::string(file.begin(), file.end()), "m.gtn");
  ASSERT_TRUE(r.isOk());
  std::vector<GtnChunkInfo> targets = {(*r)->file().chunks[0], (*r)->level(0).chunks[0]};
  ASSERT_EQ(targets[0].tag, kTagFileHeader);
  ASSERT_EQ(targets[1].tag, kTagLevelHeader);
  size_t rejected = 0, tried = 0;
  for (const GtnChunkInfo& c : targets) {
    const size_t hs = 13;
    const std::vector<uint8_t> payload(file.begin() + c.offset + hs, file.begin() + c.offset + hs + c.stored_bytes);
    // Every shorter payload must fail (each field is needed), and so must one extra byte.
    for (size_t n = 0; n <= payload.size(); ++n) {
      std::vector<uint8_t> p(payload.begin(), payload.begin() + std::min(n, payload.size()));
      if (n == payload.size()) p.push_back(0);
      const Status st = memoryStatus(reframe(file, c, p));
      EXPECT_FALSE(st.isOk()) << c.tag.str() << " payload of " << p.size() << " bytes accepted";
      EXPECT_NE(st.message().find("byte offset"), std::string::npos) << st.message();
    }
    // Byte changes: never a crash; when rejected, a located message.
    for (size_t i = 0; i < payload.size(); ++i)
      for (uint8_t x : {0x01, 0x80, 0xFF}) {
        std::vector<uint8_t> p = payload;
        p[i] ^= x;
        const Status st = memoryStatus(reframe(file, c, p));
        ++tried;
        if (!st.isOk()) {
          ++rejected;
          EXPECT_NE(st.message().find("m"), std::string::npos);
        }
      }
  }
  EXPECT_GT(rejected, 0u);
  EXPECT_LT(rejected, tried);  // names, bounding boxes and metadata text may hold any bytes

  // Values a reader must reject even with valid framing.
  auto fh = [&](const std::function<void(GtnFileHeader&)>& edit, const std::string& want) {
    GtnFileHeader h;
    const size_t hs = 13;
    ASSERT_TRUE(decodeFileHeader({file.data() + targets[0].offset + hs, targets[0].stored_bytes}, 0, "x", &h).isOk());
    edit(h);
    const Status st = memoryStatus(reframe(file, targets[0], encodeFileHeader(h)));
    EXPECT_NE(st.message().find(want), std::string::npos) << st.message();
  };
  fh([](GtnFileHeader& h) { h.coord_type = ScalarType::kInt32; }, "coordinate type must be float32");
  fh([](GtnFileHeader& h) { h.level_count = 0; }, "level count is 0");
  fh([](GtnFileHeader& h) { h.level_count = 2; }, "the file holds 1 levels, the header declares 2");
  fh([](GtnFileHeader& h) { h.points = 11; }, "level 0's counts disagree with the file header");
  fh([](GtnFileHeader& h) { h.point_fields[0].components = 0; }, "has 0 components");
  // One more field: the LHDR's piece then lacks a stream size.
  fh([](GtnFileHeader& h) { h.cell_fields.push_back({"extra", 1, ScalarType::kInt8}); }, "LHDR: byte offset");
  auto lh = [&](const std::function<void(GtnLevelRecord&)>& edit, const std::string& want) {
    GtnLevelRecord l;
    const size_t hs = 13;
    const LevelRecordContext context = levelRecordContext((*r)->file().header);
    ASSERT_TRUE(
        decodeLevelRecord({file.data() + targets[1].offset + hs, targets[1].stored_bytes}, 0, "x", context, &l).isOk());
    edit(l);
    const Status st = memoryStatus(reframe(file, targets[1], encodeLevelRecord(l, context)));
    EXPECT_NE(st.message().find(want), std::string::npos) << st.message();
  };
  lh([](GtnLevelRecord& l) { l.level = 1; }, "level header says level 1");
  lh([](GtnLevelRecord& l) { l.ratio = std::nan(""); }, "ratio is not in [0, 1]");
  lh([](GtnLevelRecord& l) { l.merges = 3; }, "level 0's counts disagree");
  // The piece table.
  lh([](GtnLevelRecord& l) { l.pieces.clear(); }, "piece count is 0");
  lh([](GtnLevelRecord& l) { l.pieces[0].kind = 2; }, "piece 0 has kind 2, which this reader does not know");
  // A structured piece is one GRID chunk: the level codec's PIEC is out of order in its place.
  lh([](GtnLevelRecord& l) { l.pieces[0].kind = 1; },
     "chunk 'PIEC' out of order in level 0 (piece 0): expected 'GRID'");
  // The piece's streams must fill its PIEC exactly.
  lh([](GtnLevelRecord& l) { l.streams[0][1] += 1; }, "stream sizes (LHDR) sum to");
  lh([](GtnLevelRecord& l) { l.pieces[0].own_boundary_points = l.pieces[0].own_points + 1; },
     "piece own boundary point count");
  // A second piece and no seam table: the chunk order names the missing SEAM.
  lh(
      [](GtnLevelRecord& l) {
        l.pieces.push_back(l.pieces[0]);
        l.streams.push_back(l.streams[0]);
        l.pieces[0].tets = 1;
        l.pieces[1].tets = l.tets - 1;
        l.pieces[0].own_points = l.pieces[1].own_points = 0;
      },
      "has several pieces but no 'SEAM' chunk");
}

TEST(GtnContainer, CorruptZstdFrameWithValidChecksumRejected) {
  std::vector<uint8_t> chunk;
  const std::vector<uint8_t> payload = pattern(5000, 3, true);
  appendGtnChunk(chunk, kTagPiece, payload, false, true, 3);
  ASSERT_TRUE(chunk[4] & kChunkZstd);
  auto check = [&](std::vector<uint8_t> c, const std::string& want) {
    const size_t body = c.size() - 8;
    const uint64_t sum = gtnChecksum({c.data(), body});
    for (int i = 0; i < 8; ++i) c[body + i] = static_cast<uint8_t>(sum >> (8 * i));
    ChunkHeader h;
    size_t needed;
    ASSERT_TRUE(parseGtnChunkHeader(c, 16, c.size(), "z.gtn", &h, &needed).isOk());
    auto opened = openGtnChunk(h, c, "z.gtn");
    ASSERT_FALSE(opened.isOk()) << want;
    EXPECT_NE(opened.status().message().find(want), std::string::npos) << opened.status().message();
  };
  std::vector<uint8_t> c = chunk;
  c[13] = static_cast<uint8_t>(c[13] + 1);  // raw_size one more than the frame holds
  check(c, "decompresses to 5000 bytes, not the declared 5001");
  c = chunk;
  c[13] = static_cast<uint8_t>(c[13] - 1);  // one less
  check(c, "more than the declared 4999");
  c = chunk;
  for (size_t i = 21; i < 29; ++i) c[i] ^= 0x5A;  // the frame header
  check(c, "zstd payload of chunk 'PIEC' is corrupt");
  // A valid chunk opens to its payload.
  ChunkHeader h;
  size_t needed;
  ASSERT_TRUE(parseGtnChunkHeader(chunk, 16, chunk.size(), "z.gtn", &h, &needed).isOk());
  auto ok = openGtnChunk(h, chunk, "z.gtn");
  ASSERT_TRUE(ok.isOk());
  EXPECT_EQ(ok.value(), payload);
}

// A chunk handed over with its buffer opens to the payload the span overload gives (a stored
// payload in the same buffer, a compressed one decompressed), and a damaged one fails alike.
TEST(GtnContainer, ChunkOpensInItsOwnBuffer) {
  for (bool zstd : {false, true}) {
    SCOPED_TRACE(zstd ? "zstd" : "stored");
    const std::vector<uint8_t> payload = pattern(300000, 9, zstd);
    std::vector<uint8_t> chunk;
    appendGtnChunk(chunk, kTagPiece, payload, false, zstd, 3);
    ASSERT_EQ((chunk[4] & kChunkZstd) != 0, zstd);
    ChunkHeader h;
    size_t needed;
    ASSERT_TRUE(parseGtnChunkHeader(chunk, 16, chunk.size(), "z.gtn", &h, &needed).isOk());
    auto viewed = openGtnChunk(h, std::span<const uint8_t>(chunk), "z.gtn");
    auto owned = openGtnChunk(h, std::vector<uint8_t>(chunk), "z.gtn");
    ASSERT_TRUE(viewed.isOk()) << viewed.status().message();
    ASSERT_TRUE(owned.isOk()) << owned.status().message();
    EXPECT_TRUE(owned.value() == payload);
    EXPECT_TRUE(viewed.value() == payload);
    std::vector<uint8_t> bad = chunk;
    bad[bad.size() / 2] ^= 0x10;
    auto a = openGtnChunk(h, std::span<const uint8_t>(bad), "z.gtn");
    auto b = openGtnChunk(h, std::move(bad), "z.gtn");
    ASSERT_FALSE(a.isOk());
    ASSERT_FALSE(b.isOk());
    EXPECT_EQ(a.status().message(), b.status().message());
    EXPECT_NE(b.status().message().find("checksum mismatch"), std::string::npos) << b.status().message();
    // A buffer of another size than the header's chunk is refused.
    std::vector<uint8_t> shorter(chunk.begin(), chunk.end() - 1);
    EXPECT_FALSE(openGtnChunk(h, std::move(shorter), "z.gtn").isOk());
  }
}

TEST(GtnContainer, WriterRejectsBadInput) {
  EncodedLevel l0 = handMadeLevel(0, 10, 20);
  EXPECT_EQ(assembleGtn({}, opts()).status().code(), StatusCode::kUsage);
  EncodedLevel wrong_level = handMadeLevel(0, 10, 20);
  wrong_level.header.level = 1;
  EXPECT_FALSE(assembleGtn({&wrong_level}, opts()).isOk());
  EncodedLevel l1 = handMadeLevel(1, 5, 5);
  l1.header.point_fields.pop_back();
  EXPECT_NE(assembleGtn({&l0, &l1}, opts()).status().message().find("field list"), std::string::npos);
  EncodedLevel missing_stream = handMadeLevel(0, 10, 20);
  missing_stream.cell_fields.clear();
  EXPECT_FALSE(assembleGtn({&missing_stream}, opts()).isOk());
  EncodedLevel many = handMadeLevel(0, 10, 20);
  many.header.point_fields[0].components = 5000;
  EXPECT_NE(assembleGtn({&many}, opts()).status().message().find("components"), std::string::npos);
  EXPECT_FALSE(assembleGtn({&l0}, opts(), {1.5}).isOk());
  EXPECT_EQ(writeGtnFile(test::tempDir("writer-bad") + "/x.gtn", {}, opts()).code(), StatusCode::kUsage);
}

}  // namespace
}  // namespace gtn
