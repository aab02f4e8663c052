// Levels of several pieces in .gtn files (format 2.0): the piece table and seam table round trip,
// a stitched level decodes to its source, a region read (decodeLevelPieces, gtn export --box) reads
// and returns exactly the pieces asked for, damage in one piece spares the others, and files are the
// same bytes whatever the thread count.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstring>
#include <map>
#include <set>

#include "codec/codec_test_util.h"
#include "convert/import.h"
#include "format/gtn_chunk.h"
#include "format/gtn_file.h"
#include "format/gtn_reader.h"
#include "test_util.h"

namespace gtn::test {
namespace {

TetMesh fieldGrid(int n) {
  TetMesh m = gridMesh(n, n, n, 5);
  addFields(m);
  return m;
}

// The points the tetrahedra use, in the canonical form (unused points dropped).
std::multiset<std::string> canonicalTets(const TetMesh& m) {
  std::multiset<std::string> all = canonicalMesh(m), out;
  for (const std::string& k : all)
    if (k[0] == 't') out.insert(k);
  return out;
}

std::string writePieces(const TetMesh& mesh, const std::string& name, uint64_t piece_tets = kMinPieceTets,
                        bool directory = true) {
  GtnWriteOptions o;
  o.tool_version = "test";
  o.piece_tets = piece_tets;
  o.directory = directory;
  GtnLevelInput level0;
  level0.mesh = &mesh;
  const std::string path = tempDir("pieces-file") + "/" + name;
  const Status st = writeGtnFile(path, {level0}, o);
  EXPECT_TRUE(st.isOk()) << st.message();
  return path;
}

std::unique_ptr<GtnReader> openFile(const std::string& path, bool verify) {
  GtnOpenOptions o;
  o.verify = verify;
  auto r = GtnReader::open(path, o);
  EXPECT_TRUE(r.isOk()) << r.status().message();
  return r.isOk() ? std::move(r).value() : nullptr;
}

TEST(GtnPiecesFile, ALevelOfSeveralPiecesRoundTripsThroughTheFile) {
  const TetMesh m = fieldGrid(20);  // 34295 tetrahedra: 16 pieces of at most 4096
  const std::string path = writePieces(m, "grid.gtn");
  for (bool verify : {true, false}) {
    SCOPED_TRACE(verify ? "scanned" : "by directory");
    std::unique_ptr<GtnReader> r = openFile(path, verify);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->openedByDirectory(), !verify);
    EXPECT_EQ(r->file().major, kGtnMajorVersion);
    EXPECT_EQ(r->file().header.draft, kGtnDraftRevision);
    EXPECT_EQ(r->file().header.piece_tets, kMinPieceTets);
    const GtnLevelInfo& li = r->level(0);
    ASSERT_GE(li.pieces.size(), 3u);
    uint64_t tets = 0, own = 0;
    for (const PieceInfo& p : li.pieces) {
      EXPECT_LE(p.tets, kMinPieceTets);
      EXPECT_GT(p.tets, 0u);
      EXPECT_LT(p.own_points, p.points);  // every piece of a grid touches a seam
      tets += p.tets;
      own += p.own_points;
    }
    EXPECT_EQ(tets, m.numTets());
    // The chunks: LHDR, SEAM, then each piece's PIEC in piece order, which holds its 3 + 5 + 2
    // streams.
    ASSERT_EQ(li.chunks.size(), 2 + li.pieces.size());
    EXPECT_EQ(li.chunks[1].tag, kTagSeam);
    EXPECT_EQ(li.chunks[1].section, "seam");
    for (size_t p = 0; p < li.pieces.size(); ++p) {
      EXPECT_EQ(li.piece_chunk[p], 2 + p);
      const GtnChunkInfo& c = li.chunks[li.piece_chunk[p]];
      EXPECT_EQ(c.tag, kTagPiece);
      EXPECT_EQ(c.piece, p);
      ASSERT_EQ(li.piece_streams[p].size(), 10u);
      uint64_t sum = 0;
      for (uint64_t n : li.piece_streams[p]) sum += n;
      if (c.raw_bytes != 0) {  // known once the chunk was read (a scan)
        EXPECT_EQ(sum, c.raw_bytes);
      }
      EXPECT_EQ(li.pieceBytes(p), c.bytes);
    }
    // The seam table: the seam points and the own points make up the level.
    std::vector<uint8_t> payload;
    auto table = r->readSeamTable(0, &payload);
    ASSERT_TRUE(table.isOk()) << table.status().message();
    uint64_t seam = 0;
    for (const SeamClass& c : table->classes) {
      EXPECT_GE(c.pieces.size(), 2u);
      seam += c.points;
    }
    EXPECT_EQ(own + seam, m.numPoints());
    // Bytes per section still add up to the file, seams included.
    uint64_t total = 0, seam_bytes = 0;
    for (const GtnSection& s : r->sections()) {
      total += s.bytes;
      if (s.name == "seam") seam_bytes = s.bytes;
    }
    EXPECT_EQ(total, r->file().bytes);
    EXPECT_EQ(seam_bytes, li.chunks[1].bytes);
    // A level of several pieces has no single stream set.
    EXPECT_EQ(r->readLevelStreams(0).status().code(), StatusCode::kUsage);
    // Decoded as a mesh stream: the source, up to renumbering, values bit for bit.
    TetMeshBuilder b;
    DecodeStats stats;
    const Status st = r->decodeLevel(0, b, &stats);
    ASSERT_TRUE(st.isOk()) << st.message();
    EXPECT_TRUE(canonicalMesh(b.mesh()) == canonicalMesh(m));
    EXPECT_GT(stats.peak_live_vertices, 0u);
    EXPECT_LE(stats.peak_live_vertices, m.numPoints());
  }
  // gtn info --json lists the pieces, and each piece's chunks name it.
  const RunResult info = runGtn("info --json " + path);
  ASSERT_EQ(info.exit_code, 0) << info.err;
  const nlohmann::json j = nlohmann::json::parse(info.out)["levels"][0];
  std::unique_ptr<GtnReader> r = openFile(path, false);
  ASSERT_TRUE(r);
  ASSERT_EQ(j["piece_count"], r->level(0).pieces.size());
  uint64_t tets = 0, bytes = 0;
  for (const nlohmann::json& p : j["pieces"]) {
    tets += p["tets"].get<uint64_t>();
    bytes += p["bytes"].get<uint64_t>();
  }
  EXPECT_EQ(tets, m.numTets());
  uint64_t piece_chunk_bytes = 0;
  for (const nlohmann::json& c : j["chunks"])
    if (c.contains("piece")) piece_chunk_bytes += c["bytes"].get<uint64_t>();
  EXPECT_EQ(bytes, piece_chunk_bytes);
  EXPECT_EQ(j["chunks"][1]["section"], "seam");
  EXPECT_FALSE(j["chunks"][1].contains("piece"));
}

// With a merge tree and mip levels (as gtn convert writes by default), the tree indexes the stitched
// level's global ids: every stored level and every merge count simplified on the fly give the same
// mesh as from a file of one piece per level.
TEST(GtnPiecesFile, MergeTreesIndexTheStitchedLevel) {
  const std::string dir = tempDir("pieces-tree");
  const std::string vtk = dir + "/grid.vtk";
  writeFile(vtk, shearedHexGridVtk(16));
  // (The same levels: a level of several pieces stores all its vertices, so the storage bound would keep
  // fewer levels in pieces.gtn.)
  ASSERT_EQ(runGtn("convert " + vtk + " -q --levels 3 -o " + dir + "/pieces.gtn --piece-tets 4096").exit_code, 0);
  ASSERT_EQ(runGtn("convert " + vtk + " -q --levels 3 -o " + dir + "/one.gtn").exit_code, 0);
  std::unique_ptr<GtnReader> pieces = openFile(dir + "/pieces.gtn", true), one = openFile(dir + "/one.gtn", true);
  ASSERT_TRUE(pieces && one);
  ASSERT_GE(pieces->level(0).pieces.size(), 3u);
  ASSERT_EQ(one->level(0).pieces.size(), 1u);
  ASSERT_GE(pieces->levels(), 2u);
  ASSERT_EQ(pieces->levels(), one->levels());
  for (const std::string& view : {std::string("--level 1"), std::string("--ratio 0.3"), std::string("--ratio 0.8")}) {
    SCOPED_TRACE(view);
    ASSERT_EQ(runGtn("export " + dir + "/pieces.gtn " + view + " -o " + dir + "/a.vtu").exit_code, 0);
    ASSERT_EQ(runGtn("export " + dir + "/one.gtn " + view + " -o " + dir + "/b.vtu").exit_code, 0);
    auto a = importMesh({dir + "/a.vtu"}, {}), b = importMesh({dir + "/b.vtu"}, {});
    ASSERT_TRUE(a.isOk() && b.isOk());
    EXPECT_GT(a->mesh.numTets(), 0u);
    EXPECT_TRUE(canonicalMesh(a->mesh) == canonicalMesh(b->mesh));
  }
}

// A region read: decodeLevelPieces reads the level's seam table and the chosen pieces' chunks only,
// and gives those pieces' tetrahedra as the whole level has them.
TEST(GtnPiecesFile, DecodingChosenPiecesReadsOnlyTheirChunks) {
  const TetMesh m = fieldGrid(20);
  const std::string path = writePieces(m, "region.gtn");
  std::unique_ptr<GtnReader> r = openFile(path, false);
  ASSERT_TRUE(r);
  ASSERT_TRUE(r->openedByDirectory());
  const GtnLevelInfo& li = r->level(0);
  ASSERT_GE(li.pieces.size(), 4u);
  auto whole = r->decodeLevelPieces(0, {});
  ASSERT_TRUE(whole.isOk()) << whole.status().message();
  EXPECT_TRUE(whole->global_tet.empty());

  const std::vector<uint32_t> chosen = {1, 3};
  const uint64_t before = r->bytesRead();
  auto part = r->decodeLevelPieces(0, chosen);
  ASSERT_TRUE(part.isOk()) << part.status().message();
  const uint64_t read = r->bytesRead() - before;
  const uint64_t wanted = li.chunks[1].bytes + li.pieceBytes(1) + li.pieceBytes(3);
  // Each chunk read costs its bytes and one look at its framing (at most 21 bytes).
  EXPECT_GE(read, wanted);
  EXPECT_LE(read, wanted + 21 * (1 + 2 * 10));
  EXPECT_LT(read, r->file().bytes / 2);

  ASSERT_EQ(part->mesh.numTets(), li.pieces[1].tets + li.pieces[3].tets);
  ASSERT_EQ(part->global_tet.size(), part->mesh.numTets());
  for (size_t t = 0; t < part->mesh.numTets(); ++t) {
    const Tet& a = part->mesh.tets[t];
    const Tet& b = whole->mesh.tets[part->global_tet[t]];
    for (int j = 0; j < 4; ++j) ASSERT_EQ(part->global_vertex[a[j]], b[j]);
  }
  for (size_t v = 0; v < part->mesh.numPoints(); ++v)
    for (int i = 0; i < 3; ++i)
      ASSERT_EQ(part->mesh.coords[3 * v + i], whole->mesh.coords[3 * size_t{part->global_vertex[v]} + i]);
  // Chosen pieces must be increasing indices of the level.
  EXPECT_EQ(r->decodeLevelPieces(0, {3, 1}).status().code(), StatusCode::kUsage);
  EXPECT_EQ(r->decodeLevelPieces(0, {static_cast<uint32_t>(li.pieces.size())}).status().code(), StatusCode::kUsage);
}

// A damaged chunk of one piece: opening warns, the other pieces still decode, the whole level fails
// naming the chunk.
TEST(GtnPiecesFile, DamageInOnePieceSparesTheOthers) {
  const TetMesh m = fieldGrid(20);
  const std::string path = writePieces(m, "damaged.gtn");
  uint64_t offset = 0;
  {
    std::unique_ptr<GtnReader> r = openFile(path, true);
    ASSERT_TRUE(r);
    const GtnLevelInfo& li = r->level(0);
    const GtnChunkInfo& geom = li.chunks[li.piece_chunk[2]];
    ASSERT_EQ(geom.tag, kTagPiece);
    offset = geom.offset + geom.bytes / 2;
  }
  std::string bytes = readFile(path);
  bytes[offset] ^= 0x10;
  writeFile(path, bytes);
  std::vector<std::string> warnings;
  GtnOpenOptions o;
  o.verify = false;
  auto r = openGtnChecked(path, o, [&](const std::string& w) { warnings.push_back(w); });
  ASSERT_TRUE(r.isOk()) << r.status().message();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("'PIEC' (level 0, piece"), std::string::npos) << warnings[0];
  EXPECT_TRUE((*r)->decodeLevelPieces(0, {0, 1}).isOk());
  TetMeshBuilder b;
  const Status st = (*r)->decodeLevel(0, b);
  EXPECT_EQ(st.code(), StatusCode::kInvalidData);
  EXPECT_NE(st.message().find("checksum mismatch in chunk 'PIEC'"), std::string::npos) << st.message();
}

TEST(GtnPiecesFile, TheSameBytesForAnyThreadCount) {
  const std::string dir = tempDir("pieces-threads");
  const std::string vtk = dir + "/grid.vtk";
  writeFile(vtk, shearedHexGridVtk(16));
  std::string first;
  for (int threads : {1, 2, 4}) {
    // The same file name each time: the command line (without --threads) is in the file.
    const std::string out = tempDir("pieces-threads-" + std::to_string(threads)) + "/grid.gtn";
    const RunResult r =
        runGtn("convert " + vtk + " -q -o " + out + " --piece-tets 4096 --threads " + std::to_string(threads));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string bytes = readFile(out);
    if (threads == 1) {
      first = bytes;
      std::unique_ptr<GtnReader> reader = openFile(out, true);
      ASSERT_TRUE(reader);
      EXPECT_GE(reader->level(0).pieces.size(), 3u);
    } else {
      EXPECT_TRUE(bytes == first) << threads << " threads";
    }
  }
}

TEST(GtnPiecesFile, PieceSizeBelowTheMinimumIsRefused) {
  const TetMesh m = fieldGrid(4);
  GtnWriteOptions o;
  o.piece_tets = kMinPieceTets - 1;
  GtnLevelInput level0;
  level0.mesh = &m;
  const Status st = writeGtnFile(tempDir("pieces-min") + "/x.gtn", {level0}, o);
  EXPECT_EQ(st.code(), StatusCode::kUsage);
  EXPECT_NE(st.message().find("at least 4096"), std::string::npos) << st.message();

  const std::string dir = tempDir("pieces-min-cli");
  writeFile(dir + "/grid.vtk", shearedHexGridVtk(4));
  const RunResult r = runGtn("convert " + dir + "/grid.vtk -o " + dir + "/x.gtn --piece-tets 100");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--piece-tets"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("at least 4096"), std::string::npos) << r.err;
  EXPECT_FALSE(fileExists(dir + "/x.gtn"));
}

// gtn export --box and gtn decode --box: exactly the pieces whose bounding boxes meet the box.
TEST(GtnPiecesFile, ExportBoxReturnsThePiecesMeetingTheBox) {
  const TetMesh m = fieldGrid(20);
  const std::string path = writePieces(m, "box.gtn");
  const std::string dir = tempDir("pieces-box");
  std::unique_ptr<GtnReader> r = openFile(path, false);
  ASSERT_TRUE(r);
  const GtnLevelInfo& li = r->level(0);
  // A small box in the middle of piece 0's bounding box.
  double lo[3], hi[3];
  for (int i = 0; i < 3; ++i) {
    const double c = 0.5 * (li.pieces[0].bbox_min[i] + li.pieces[0].bbox_max[i]);
    lo[i] = c - 0.25;
    hi[i] = c + 0.25;
  }
  std::vector<uint32_t> want;
  uint64_t want_tets = 0;
  for (size_t p = 0; p < li.pieces.size(); ++p) {
    bool meets = true;
    for (int i = 0; i < 3; ++i) meets = meets && li.pieces[p].bbox_min[i] <= hi[i] && li.pieces[p].bbox_max[i] >= lo[i];
    if (meets) {
      want.push_back(static_cast<uint32_t>(p));
      want_tets += li.pieces[p].tets;
    }
  }
  ASSERT_FALSE(want.empty());
  ASSERT_LT(want.size(), li.pieces.size());
  char box[256];
  std::snprintf(box, sizeof box, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g", lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  RunResult run = runGtn("export " + path + " --box=" + box + " -o " + dir + "/box.vtu");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  auto exported = importMesh({dir + "/box.vtu"}, {});
  ASSERT_TRUE(exported.isOk()) << exported.status().message();
  EXPECT_EQ(exported->mesh.numTets(), want_tets);
  auto pieces = r->decodeLevelPieces(0, want);
  ASSERT_TRUE(pieces.isOk());
  EXPECT_TRUE(canonicalTets(exported->mesh) == canonicalTets(pieces->mesh));
  // gtn decode reads the same.
  run = runGtn("decode " + path + " --json --box=" + box);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(nlohmann::json::parse(run.out)["tets"], want_tets);
  // A box that holds every piece gives the level.
  run = runGtn("export " + path + " --box=-1e9,-1e9,-1e9,1e9,1e9,1e9 -o " + dir + "/all.vtu");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  auto all = importMesh({dir + "/all.vtu"}, {});
  ASSERT_TRUE(all.isOk());
  EXPECT_EQ(all->mesh.numTets(), m.numTets());
  // Bad boxes: a clear error naming the option.
  for (const std::string& bad : {std::string("1,2,3"), std::string("0,0,0,1,1,x"), std::string("2,0,0,1,1,1"),
                                 std::string("1e9,1e9,1e9,2e9,2e9,2e9")}) {
    run = runGtn("export " + path + " --box=" + bad + " -o " + dir + "/bad.vtu");
    EXPECT_NE(run.exit_code, 0) << bad;
    EXPECT_NE(run.err.find("--box"), std::string::npos) << run.err;
    EXPECT_FALSE(fileExists(dir + "/bad.vtu"));
  }
  run = runGtn("export " + path + " --box=0,0,0,1,1,1 --ratio 0.5 -o " + dir + "/bad.vtu");
  EXPECT_NE(run.exit_code, 0);
  // An empty box, a ratio that is not a number and a negative level are usage errors (exit 2), for
  // export and decode alike, naming the option; none is taken for the whole level 0.
  for (const std::string& bad :
       {std::string("--box="), std::string("--ratio nan"), std::string("--ratio -nan"), std::string("--level -1")}) {
    for (const std::string& command : {"export " + path + " -o " + dir + "/bad.vtu ", "decode " + path + " "}) {
      run = runGtn(command + bad);
      EXPECT_EQ(run.exit_code, 2) << command << bad << ": " << run.err;
      EXPECT_NE(run.err.find(bad.substr(0, bad.find_first_of("= "))), std::string::npos) << run.err;
      EXPECT_EQ(run.err.find("18446744073709551615"), std::string::npos) << run.err;
      EXPECT_FALSE(fileExists(dir + "/bad.vtu"));
    }
  }
}

// gtn decode of a level of several pieces decodes them straight into one mesh: the counts and fields
// of one-piece file's decode, with --fields too.
TEST(GtnPiecesFile, DecodeReportsTheWholeLevelOfSeveralPieces) {
  const std::string dir = tempDir("pieces-decode");
  const std::string vtk = dir + "/grid.vtk";
  writeFile(vtk, shearedHexGridVtk(16, false, true));
  ASSERT_EQ(runGtn("convert " + vtk + " -q -o " + dir + "/pieces.gtn --piece-tets 4096").exit_code, 0);
  ASSERT_EQ(runGtn("convert " + vtk + " -q -o " + dir + "/one.gtn").exit_code, 0);
  for (const std::string& extra : {std::string(""), std::string(" --threads 1")}) {
    const RunResult a = runGtn("decode --json " + dir + "/pieces.gtn" + extra);
    const RunResult b = runGtn("decode --json " + dir + "/one.gtn" + extra);
    ASSERT_EQ(a.exit_code, 0) << a.err;
    ASSERT_EQ(b.exit_code, 0) << b.err;
    const nlohmann::json ja = nlohmann::json::parse(a.out), jb = nlohmann::json::parse(b.out);
    EXPECT_EQ(ja["points"], jb["points"]);
    EXPECT_EQ(ja["tets"], jb["tets"]);
    EXPECT_EQ(ja["fields"], jb["fields"]);
    EXPECT_GT(ja["tets"].get<uint64_t>(), 4096u);
  }
  const RunResult one_field = runGtn("decode --json --fields block " + dir + "/pieces.gtn");
  ASSERT_EQ(one_field.exit_code, 0) << one_field.err;
  const nlohmann::json j = nlohmann::json::parse(one_field.out);
  ASSERT_EQ(j["fields"].size(), 1u);
  EXPECT_EQ(j["fields"][0]["name"], "block");
  const RunResult bad = runGtn("decode --fields nosuch " + dir + "/pieces.gtn");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("nosuch"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace gtn::test
