// One .gtn from a mesh held in parts (format/gtn_parts.h, codec/pieces.h "A level held in parts"):
// parts simulated by threads, each holding its share of a generated grid with copies of the points it
// shares; the file validates and decodes to the whole mesh, each part's pieces are its own, and the
// parts' disagreements are refused on every part.
#include "format/gtn_parts.h"

#include <gtest/gtest.h>

#include <barrier>
#include <cstring>
#include <set>
#include <thread>

#include "codec/codec_test_util.h"
#include "codec/pieces_check.h"
#include "format/file_io.h"
#include "format/gtn_reader.h"
#include "test_util.h"
#include "validate/validator.h"

namespace gtn::test {
namespace {

// Parts as threads: gather and broadcast through shared slots between barriers.
struct Hub {
  explicit Hub(int n) : slots(n), sync(n) {}
  std::vector<std::vector<uint8_t>> slots;
  std::vector<uint8_t> shared;
  std::barrier<> sync;
};

class ThreadExchange : public PartExchange {
 public:
  ThreadExchange(Hub& hub, int part) : hub_(hub), part_(part) {}
  int part() const override { return part_; }
  int parts() const override { return static_cast<int>(hub_.slots.size()); }
  Status gather(const std::vector<uint8_t>& mine, std::vector<std::vector<uint8_t>>* all) override {
    hub_.slots[part_] = mine;
    hub_.sync.arrive_and_wait();
    if (part_ == 0) *all = hub_.slots;
    hub_.sync.arrive_and_wait();
    return Status::ok();
  }
  Status broadcast(std::vector<uint8_t>* bytes) override {
    if (part_ == 0) hub_.shared = *bytes;
    hub_.sync.arrive_and_wait();
    if (part_ != 0) *bytes = hub_.shared;
    hub_.sync.arrive_and_wait();
    return Status::ok();
  }

 private:
  Hub& hub_;
  int part_;
};

// A part: the tetrahedra `tets` of `whole` with the points they use (in reverse source order, so
// that local indices differ from the source's), plus `extra` points; keys by source index or by
// coordinates.
struct Part {
  TetMesh mesh;
  std::vector<PointKey> keys;
  bool coordinate_keys = false;
};

Part makePart(const TetMesh& whole, const std::vector<uint32_t>& tets, const std::vector<uint32_t>& extra,
              bool coordinate_keys) {
  std::vector<uint32_t> used(extra);
  for (uint32_t t : tets)
    for (uint32_t v : whole.tets[t]) used.push_back(v);
  std::sort(used.begin(), used.end(), std::greater<>());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  std::map<uint32_t, uint32_t> local;
  Part p;
  p.coordinate_keys = coordinate_keys;
  p.mesh.coord_type = whole.coord_type;
  for (const Field& f : whole.point_fields) p.mesh.point_fields.emplace_back(f.name, f.components, f.type, used.size());
  for (const Field& f : whole.cell_fields) p.mesh.cell_fields.emplace_back(f.name, f.components, f.type, tets.size());
  for (size_t k = 0; k < used.size(); ++k) {
    const uint32_t v = used[k];
    local[v] = static_cast<uint32_t>(k);
    for (int i = 0; i < 3; ++i) p.mesh.coords.push_back(whole.coords[3 * size_t{v} + i]);
    for (size_t f = 0; f < whole.point_fields.size(); ++f) {
      const size_t ib = whole.point_fields[f].components * whole.point_fields[f].valueSize();
      std::memcpy(&p.mesh.point_fields[f].bytes[k * ib], &whole.point_fields[f].bytes[v * ib], ib);
    }
    PointKey key{v, 0, 0};
    if (coordinate_keys)
      for (int i = 0; i < 3; ++i) std::memcpy(&key[i], &whole.coords[3 * size_t{v} + i], 8);
    p.keys.push_back(key);
  }
  for (size_t k = 0; k < tets.size(); ++k) {
    Tet t;
    for (int j = 0; j < 4; ++j) t[j] = local.at(whole.tets[tets[k]][j]);
    p.mesh.tets.push_back(t);
    for (size_t f = 0; f < whole.cell_fields.size(); ++f) {
      const size_t ib = whole.cell_fields[f].components * whole.cell_fields[f].valueSize();
      std::memcpy(&p.mesh.cell_fields[f].bytes[k * ib], &whole.cell_fields[f].bytes[tets[k] * ib], ib);
    }
  }
  return p;
}

// The tetrahedra of `whole` cut into `n` slabs along x by centroid.
std::vector<std::vector<uint32_t>> slabs(const TetMesh& whole, int n) {
  double lo = 1e300, hi = -1e300;
  for (size_t v = 0; v < whole.numPoints(); ++v) {
    lo = std::min(lo, whole.point(v)[0]);
    hi = std::max(hi, whole.point(v)[0]);
  }
  std::vector<std::vector<uint32_t>> out(n);
  for (size_t t = 0; t < whole.numTets(); ++t) {
    double c = 0;
    for (uint32_t v : whole.tets[t]) c += whole.point(v)[0] / 4;
    out[std::min(n - 1, static_cast<int>((c - lo) / (hi - lo) * n))].push_back(static_cast<uint32_t>(t));
  }
  return out;
}

struct Written {
  std::vector<Status> status;
  std::vector<PartsWriteReport> reports;
};

Written writeParts(const std::string& path, const std::vector<Part>& parts, uint64_t piece_tets = kMinPieceTets) {
  Hub hub(static_cast<int>(parts.size()));
  Written w;
  w.status.resize(parts.size());
  w.reports.resize(parts.size());
  std::vector<std::thread> threads;
  for (size_t q = 0; q < parts.size(); ++q)
    threads.emplace_back([&, q] {
      ThreadExchange ex(hub, static_cast<int>(q));
      GtnWriteOptions o;
      o.tool_version = "test";
      o.command_line = "parts test";
      o.piece_tets = piece_tets;
      w.status[q] =
          writeGtnFromParts(path, parts[q].mesh, parts[q].keys, parts[q].coordinate_keys, ex, o, &w.reports[q]);
    });
  for (std::thread& t : threads) t.join();
  return w;
}

TetMesh decodeFile(const std::string& path, std::vector<PieceInfo>* pieces = nullptr, std::string* command = nullptr) {
  auto r = GtnReader::open(path, {});
  EXPECT_TRUE(r.isOk()) << r.status().message();
  if (!r.isOk()) return {};
  if (pieces) *pieces = (*r)->level(0).pieces;
  if (command) *command = (*r)->file().header.command_line;
  EXPECT_EQ((*r)->levels(), 1u);
  TetMeshBuilder b;
  const Status st = (*r)->decodeLevel(0, b);
  EXPECT_TRUE(st.isOk()) << st.message();
  return b.mesh();
}

void expectValid(const std::string& path) {
  auto report = validateGtnFile(path, {});
  ASSERT_TRUE(report.isOk()) << report.status().message();
  EXPECT_FALSE(report->hasErrors()) << report->toText(path);
}

TetMesh fieldGrid(int n) {
  TetMesh m = gridMesh(n, n, n, 5);
  addFields(m);
  return m;
}

TEST(GtnParts, TwoPartsMakeOneFileThatDecodesToTheWholeMesh) {
  const TetMesh whole = fieldGrid(20);  // 34295 tetrahedra
  const auto share = slabs(whole, 2);
  for (bool coordinate_keys : {false, true}) {
    SCOPED_TRACE(coordinate_keys ? "keys: coordinates" : "keys: global ids");
    const std::vector<Part> parts = {makePart(whole, share[0], {}, coordinate_keys),
                                     makePart(whole, share[1], {}, coordinate_keys)};
    const std::string path = tempDir("parts") + "/two.gtn";
    const Written w = writeParts(path, parts);
    for (const Status& st : w.status) ASSERT_TRUE(st.isOk()) << st.message();
    expectValid(path);
    std::vector<PieceInfo> pieces;
    std::string command;
    const TetMesh got = decodeFile(path, &pieces, &command);
    EXPECT_TRUE(canonicalMesh(got) == canonicalMesh(whole));
    EXPECT_EQ(got.numPoints(), whole.numPoints());  // the shared points once
    // Each part coded its own pieces: the file's first pieces hold part 0's tetrahedra, the rest
    // part 1's.
    const std::vector<uint32_t>& per_part = w.reports[1].pieces_per_part;
    ASSERT_EQ(per_part.size(), 2u);
    EXPECT_EQ(w.reports[0].pieces_per_part, per_part);
    EXPECT_GE(per_part[0], 2u);
    EXPECT_GE(per_part[1], 2u);
    ASSERT_EQ(pieces.size(), per_part[0] + per_part[1]);
    uint64_t first = 0;
    for (size_t p = 0; p < per_part[0]; ++p) first += pieces[p].tets;
    EXPECT_EQ(first, share[0].size());
    EXPECT_NE(command.find("(2 parts: " + std::to_string(per_part[0]) + " " + std::to_string(per_part[1]) + " pieces)"),
              std::string::npos)
        << command;
    EXPECT_GT(w.reports[0].seam_points, 0u);
  }
  // With one piece per part, part 0 receives the parts' boundaries only.
  const Written w =
      writeParts(tempDir("parts") + "/two-big.gtn",
                 {makePart(whole, share[0], {}, false), makePart(whole, share[1], {}, false)}, kDefaultPieceTets);
  for (const Status& st : w.status) ASSERT_TRUE(st.isOk()) << st.message();
  EXPECT_EQ(w.reports[0].pieces_per_part, (std::vector<uint32_t>{1, 1}));
  EXPECT_LT(w.reports[0].exposed_points, whole.numPoints() / 2);
}

TEST(GtnParts, OnePartPerThreeSlabsAndAnEmptyPart) {
  const TetMesh whole = fieldGrid(14);
  const auto share = slabs(whole, 3);
  const std::vector<Part> parts = {makePart(whole, share[0], {}, false), makePart(whole, {}, {}, false),
                                   makePart(whole, share[1], {}, false), makePart(whole, share[2], {}, false)};
  const std::string path = tempDir("parts") + "/four.gtn";
  const Written w = writeParts(path, parts);
  for (const Status& st : w.status) ASSERT_TRUE(st.isOk()) << st.message();
  expectValid(path);
  EXPECT_TRUE(canonicalMesh(decodeFile(path)) == canonicalMesh(whole));
  EXPECT_EQ(w.reports[0].pieces_per_part[1], 0u);
}

TEST(GtnParts, OnePartIsOnePieceWhenSmall) {
  const TetMesh whole = fieldGrid(8);
  const std::string path = tempDir("parts") + "/one.gtn";
  const Written w = writeParts(path, {makePart(whole, slabs(whole, 1)[0], {}, false)});
  ASSERT_TRUE(w.status[0].isOk()) << w.status[0].message();
  expectValid(path);
  std::vector<PieceInfo> pieces;
  EXPECT_TRUE(canonicalMesh(decodeFile(path, &pieces)) == canonicalMesh(whole));
  EXPECT_EQ(pieces.size(), 1u);
}

// Unused points: one held by both parts is written once; one that part 1 holds unused and part 0
// uses inside its share is part 0's.
TEST(GtnParts, UnusedPointsAreWrittenOnce) {
  TetMesh whole = fieldGrid(12);
  const auto share = slabs(whole, 2);
  const size_t n = whole.numPoints();
  whole.coords.insert(whole.coords.end(), {-5.0, -5.0, -5.0});
  for (Field& f : whole.point_fields) f.bytes.resize(f.bytes.size() + f.components * f.valueSize(), 7);
  uint32_t inside = kNoIndex;  // a point part 0's tetrahedra use, not on its boundary
  {
    Part p0 = makePart(whole, share[0], {}, false);
    auto plan = planPart(p0.mesh, kMinPieceTets);
    ASSERT_TRUE(plan.isOk());
    std::set<uint32_t> exposed(plan->exposed.begin(), plan->exposed.end());
    for (size_t v = 0; v < p0.mesh.numPoints() && inside == kNoIndex; ++v)
      if (!exposed.count(static_cast<uint32_t>(v))) inside = static_cast<uint32_t>(p0.keys[v][0]);
  }
  ASSERT_NE(inside, kNoIndex);
  const std::vector<Part> parts = {makePart(whole, share[0], {static_cast<uint32_t>(n)}, false),
                                   makePart(whole, share[1], {static_cast<uint32_t>(n), inside}, false)};
  const std::string path = tempDir("parts") + "/unused.gtn";
  const Written w = writeParts(path, parts);
  for (const Status& st : w.status) ASSERT_TRUE(st.isOk()) << st.message();
  expectValid(path);
  const TetMesh got = decodeFile(path);
  EXPECT_EQ(got.numPoints(), whole.numPoints());
  EXPECT_TRUE(canonicalMesh(got) == canonicalMesh(whole));
}

TEST(GtnParts, PartsThatDisagreeFailOnEveryPartAndWriteNothing) {
  const TetMesh whole = fieldGrid(12);
  const auto share = slabs(whole, 2);
  const std::string path = tempDir("parts") + "/bad.gtn";
  std::remove(path.c_str());
  {
    // A shared point's copy moved on part 1.
    std::vector<Part> parts = {makePart(whole, share[0], {}, false), makePart(whole, share[1], {}, false)};
    std::set<PointKey> keys0(parts[0].keys.begin(), parts[0].keys.end());
    size_t shared = 0;
    while (!keys0.count(parts[1].keys[shared])) ++shared;
    parts[1].mesh.coords[3 * shared] += 1e-9;
    const Written w = writeParts(path, parts);
    for (const Status& st : w.status) {
      EXPECT_EQ(st.code(), StatusCode::kInvalidData);
      EXPECT_NE(st.message().find(path + ": parts 0 and 1 hold different coordinates"), std::string::npos)
          << st.message();
    }
    EXPECT_FALSE(isRegularFile(path));
  }
  {
    // Part 1 without the point fields.
    std::vector<Part> parts = {makePart(whole, share[0], {}, false), makePart(whole, share[1], {}, false)};
    parts[1].mesh.point_fields.clear();
    const Written w = writeParts(path, parts);
    for (const Status& st : w.status)
      EXPECT_NE(st.message().find("part 1 has another coordinate type or other fields than part 0"), std::string::npos)
          << st.message();
    EXPECT_FALSE(isRegularFile(path));
  }
  {
    // Part 0's own failure: a key list of the wrong length.
    std::vector<Part> parts = {makePart(whole, share[0], {}, false), makePart(whole, share[1], {}, false)};
    parts[0].keys.pop_back();
    const Written w = writeParts(path, parts);
    for (const Status& st : w.status) {
      EXPECT_EQ(st.code(), StatusCode::kUsage);
      EXPECT_NE(st.message().find(path + ": part 0: one key per point is needed"), std::string::npos) << st.message();
    }
    EXPECT_FALSE(isRegularFile(path));
  }
}

// The API step by step for two parts (what writeGtnFromParts exchanges), and the part check:
// partLosslessMismatch finds a piece whose streams do not give back the part.
TEST(GtnParts, EachPartChecksItsPiecesAgainstTheAssembledLevel) {
  const TetMesh whole = fieldGrid(16);
  const auto share = slabs(whole, 2);
  const std::vector<Part> parts = {makePart(whole, share[0], {}, false), makePart(whole, share[1], {}, false)};
  std::vector<PartPlan> plans;
  std::vector<PartExposed> exposed;
  for (const Part& p : parts) {
    auto plan = planPart(p.mesh, kMinPieceTets);
    ASSERT_TRUE(plan.isOk()) << plan.status().message();
    PartExposed e;
    e.pieces = plan->pieces;
    for (uint32_t v : plan->exposed) e.keys.push_back(p.keys[v]);
    e.uses_first = plan->uses_first;
    e.uses = plan->uses;
    plans.push_back(std::move(plan).value());
    exposed.push_back(std::move(e));
  }
  auto seams = planSeams(exposed);
  ASSERT_TRUE(seams.isOk()) << seams.status().message();
  EXPECT_TRUE(seams->orphans.empty());
  std::vector<EncodedPart> encoded;
  for (size_t q = 0; q < parts.size(); ++q) {
    auto e = encodePart(parts[q].mesh, plans[q], seams->classes, seams->first_piece[q], seams->status[q]);
    ASSERT_TRUE(e.isOk()) << e.status().message();
    encoded.push_back(std::move(e).value());
  }
  // The seam vertices' values, from their source copies.
  TetMesh seam_mesh;
  seam_mesh.coord_type = whole.coord_type;
  for (const Field& f : whole.point_fields)
    seam_mesh.point_fields.emplace_back(f.name, f.components, f.type, seams->seam_source.size());
  for (size_t s = 0; s < seams->seam_source.size(); ++s) {
    const auto [q, i] = seams->seam_source[s];
    const uint32_t v = plans[q].exposed[i];
    for (int c = 0; c < 3; ++c) seam_mesh.coords.push_back(parts[q].mesh.coords[3 * size_t{v} + c]);
    for (size_t f = 0; f < seam_mesh.point_fields.size(); ++f) {
      const size_t ib = seam_mesh.point_fields[f].components * seam_mesh.point_fields[f].valueSize();
      std::memcpy(&seam_mesh.point_fields[f].bytes[s * ib], &parts[q].mesh.point_fields[f].bytes[v * ib], ib);
    }
  }
  std::vector<EncodedPart> sent = encoded;  // what the parts send: the streams
  auto level = assembleParts(std::move(sent), *seams, seam_mesh);
  ASSERT_TRUE(level.isOk()) << level.status().message();
  EXPECT_EQ(level->header.points, whole.numPoints());
  EXPECT_EQ(level->header.tets, whole.numTets());
  for (size_t q = 0; q < parts.size(); ++q)
    EXPECT_EQ(partLosslessMismatch(parts[q].mesh, encoded[q], seams->first_piece[q], piecedViewOf(*level)), "");
  // The whole level decodes to the whole mesh, its boundary that of the whole mesh.
  auto decoded = decodePieces(piecedViewOf(*level), {}, "parts");
  ASSERT_TRUE(decoded.isOk()) << decoded.status().message();
  EXPECT_TRUE(canonicalMesh(decoded->mesh) == canonicalMesh(whole));
  EXPECT_EQ(level->header.boundary_triangles, decoded->boundary.size());
  // Part 1's mesh with one cell value changed no longer matches what its pieces decode to.
  TetMesh changed = parts[1].mesh;
  changed.cell_fields[0].bytes[0] ^= 1;
  EXPECT_NE(partLosslessMismatch(changed, encoded[1], seams->first_piece[1], piecedViewOf(*level))
                .find("has other field values"),
            std::string::npos);
}

}  // namespace
}  // namespace gtn::test
