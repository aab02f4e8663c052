// bench-simplify: per dataset, the static ranking's time and throughput, the cost of on-the-fly
// simplification relative to plain decoding ("filter s" = the filter's own time plus decoding the
// first n merges of the MTRE payload, "tree s" = that decoding alone), and what each mip level keeps (points, tetrahedra,
// total volume and total mass change relative to level 0, stored bytes of level and merge tree).
//
// Usage: bench-simplify [--data DIR] [--repeat R] [DATASET...]   (datasets: spx, cornell, bluntfin,
// combustion, bluntfin5, combustion5; default all)
#include <time.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "codec/level_codec.h"
#include "codec/merge_tree_coder.h"
#include "convert/import.h"
#include "format/gtn_file.h"
#include "format/gtn_reader.h"
#include "mesh/mesh_stats.h"
#include "mesh/predicates.h"
#include "simplify/levels.h"
#include "simplify/ranking.h"
#include "simplify/stream_simplifier.h"

namespace {

using namespace gtn;

struct Dataset {
  std::string name;
  std::vector<std::string> files;
  int split;
};

// The decoder's event stream, recorded once and replayed, so that the filter's own cost can be timed
// in short runs apart from the decoding.
class RecordingSink : public MeshSink {
 public:
  Status beginLevel(const LevelHeader& h) override {
    header = h;
    for (const FieldDesc& d : h.point_fields) item_bytes += d.itemBytes();
    for (const FieldDesc& d : h.cell_fields) cell_bytes += d.itemBytes();
    return Status::ok();
  }
  Status vertex(uint32_t id, const double* xyz, const uint8_t* values) override {
    events.push_back({kVertex, {id, 0, 0, 0}});
    coords.insert(coords.end(), xyz, xyz + 3);
    if (item_bytes) values_.insert(values_.end(), values, values + item_bytes);
    return Status::ok();
  }
  Status boundaryTriangle(const uint32_t* v) override {
    events.push_back({kTriangle, {v[0], v[1], v[2], 0}});
    return Status::ok();
  }
  Status endBoundary() override {
    events.push_back({kEndBoundary, {}});
    return Status::ok();
  }
  Status tet(const uint32_t* v, const uint8_t* cell) override {
    events.push_back({kTet, {v[0], v[1], v[2], v[3]}});
    if (cell_bytes) cells.insert(cells.end(), cell, cell + cell_bytes);
    return Status::ok();
  }
  Status retireVertex(uint32_t id) override {
    events.push_back({kRetire, {id, 0, 0, 0}});
    return Status::ok();
  }
  Status endLevel() override { return Status::ok(); }

  void replay(MeshSink& out) const {
    (void)out.beginLevel(header);
    size_t nv = 0, nt = 0;
    for (const Event& e : events) {
      switch (e.kind) {
        case kVertex:
          (void)out.vertex(e.v[0], &coords[3 * nv], item_bytes ? &values_[item_bytes * nv] : nullptr);
          ++nv;
          break;
        case kTriangle: (void)out.boundaryTriangle(e.v); break;
        case kEndBoundary: (void)out.endBoundary(); break;
        case kTet:
          (void)out.tet(e.v, cell_bytes ? &cells[cell_bytes * nt] : nullptr);
          ++nt;
          break;
        case kRetire: (void)out.retireVertex(e.v[0]); break;
      }
    }
    (void)out.endLevel();
  }

 private:
  enum Kind : uint8_t { kVertex, kTriangle, kEndBoundary, kTet, kRetire };
  struct Event {
    Kind kind;
    uint32_t v[4];
  };
  LevelHeader header;
  size_t item_bytes = 0, cell_bytes = 0;
  std::vector<Event> events;
  std::vector<double> coords;
  std::vector<uint8_t> values_, cells;
};

using gtn::bench::threadSeconds;

// Total volume and total mass (density = the ranking's field, 1 without one).
void volumeMass(const TetMesh& m, const std::string& field, double* volume, double* mass) {
  const Field* f = field.empty() ? nullptr : m.findPointField(field);
  *volume = *mass = 0;
  for (const Tet& t : m.tets) {
    const double v = signedVolume(m.point(t[0]), m.point(t[1]), m.point(t[2]), m.point(t[3]));
    double rho = 1;
    if (f) rho = 0.25 * (f->get(t[0], 0) + f->get(t[1], 0) + f->get(t[2], 0) + f->get(t[3], 0));
    *volume += v;
    *mass += rho * v;
  }
}

uint64_t levelBytes(const EncodedLevel& e) {
  uint64_t b = e.boundary.size() + e.connectivity.size() + e.geometry.size();
  for (const auto& s : e.point_fields) b += s.size();
  for (const auto& s : e.cell_fields) b += s.size();
  return b;
}

int run(const Dataset& d, int repeat) {
  ImportOptions io;
  io.split = d.split;
  auto imported = importMesh(d.files, io);
  if (!imported.isOk()) {
    std::fprintf(stderr, "%s: %s\n", d.name.c_str(), imported.status().message().c_str());
    return 1;
  }
  const TetMesh& mesh = imported->mesh;
  RankingStats stats;
  const std::clock_t cpu0 = std::clock();
  auto tree = rankMerges(mesh, RankingOptions{}, &stats);
  const double cpu = double(std::clock() - cpu0) / CLOCKS_PER_SEC;
  if (!tree.isOk()) {
    std::fprintf(stderr, "%s: %s\n", d.name.c_str(), tree.status().message().c_str());
    return 1;
  }
  std::printf("\n== %s (split %d): %zu points, %zu tets, field '%s'\n", d.name.c_str(), d.split, mesh.numPoints(),
              mesh.numTets(), stats.field.c_str());
  std::printf(
      "ranking: %.3f s wall, %.3f s CPU, %.0f tets/s (CPU), %llu merges (%llu boundary), %llu popped, %llu rejected, "
      "%llu evaluations\n",
      stats.seconds, cpu, mesh.numTets() / cpu, (unsigned long long)stats.merges,
      (unsigned long long)stats.boundary_merges, (unsigned long long)stats.popped, (unsigned long long)stats.rejected,
      (unsigned long long)stats.evaluations);

  // On-the-fly cost: decode level 0 to a null sink, then through the filter at several ratios.
  auto enc = encodeLevel(mesh, EncodeOptions{});
  if (!enc.isOk()) {
    std::fprintf(stderr, "%s: %s\n", d.name.c_str(), enc.status().message().c_str());
    return 1;
  }
  // The level as its decoder numbers it: what the merge tree is decoded against.
  auto decodedMesh = [&](const EncodedLevel& e) {
    TetMeshBuilder b;
    (void)decodeLevel(e.header, payloadOf(e), b, nullptr, d.name);
    return std::move(b.mesh());
  };
  const TetMesh decoded0 = decodedMesh(*enc);
  auto payload = encodeMergeTree(*tree, enc->vertex_order, &mesh);
  auto stream_tree = decodeMergeTree(*payload, mesh.numPoints(), d.name, &decoded0);
  if (!payload.isOk() || !stream_tree.isOk()) return 1;
  const LevelPayload lp = payloadOf(*enc);
  // Plain and filtered decodes alternate, and each keeps its best thread CPU time, so that load from
  // other processes affects both alike.
  // Overhead = decoding the merge tree plus the filter's own time (replaying the recorded stream
  // through it, less replaying it into a null sink), over the plain decode; every figure is the best of `repeat` runs of thread CPU time,
  // which keeps load from other processes out of the short runs.
  double last_tree_decode = 0;
  auto compare = [&](const LevelHeader& header, const LevelPayload& payload, const TetMesh& decoded,
                     const MergeTree& st, const std::vector<uint8_t>& tree_bytes, uint64_t n, double* plain,
                     double* filter, uint64_t* out) {
    RecordingSink rec;
    (void)decodeLevel(header, payload, rec, nullptr, d.name);
    *plain = 1e30;
    double null_replay = 1e30, simp_replay = 1e30;
    for (int r = 0; r < repeat; ++r) {
      double t0 = threadSeconds();
      CountingSink a;
      (void)decodeLevel(header, payload, a, nullptr, d.name);
      *plain = std::min(*plain, threadSeconds() - t0);
    }
    for (int r = 0; r < 4 * repeat; ++r) {
      double t0 = threadSeconds();
      CountingSink a;
      rec.replay(a);
      null_replay = std::min(null_replay, threadSeconds() - t0);
      t0 = threadSeconds();
      CountingSink b;
      StreamSimplifier simp(st, n, b);
      rec.replay(simp);
      simp_replay = std::min(simp_replay, threadSeconds() - t0);
      *out = b.tets;
    }
    double tree_decode = 1e30;  // reading the MTRE chunk is part of the price
    for (int r = 0; r < repeat; ++r) {
      const double t0 = threadSeconds();
      (void)decodeMergeTree(tree_bytes, st.points(), d.name, &decoded, n);  // as the reader: the first n merges
      tree_decode = std::min(tree_decode, threadSeconds() - t0);
    }
    *filter = std::max(0.0, simp_replay - null_replay) + tree_decode;
    last_tree_decode = tree_decode;
  };
  std::printf("merge tree: %zu bytes (%.2f bits/vertex), level streams %llu bytes\n", payload->size(),
              8.0 * payload->size() / mesh.numPoints(), (unsigned long long)levelBytes(*enc));
  std::printf("on the fly from level 0 (no stored levels):\n");
  std::printf("%8s %10s %10s %10s %10s %9s\n", "ratio", "tets out", "decode s", "filter s", "tree s", "overhead");
  // Ratio 0 needs no filter (readers decode the level as it is). 0.45, 0.7 and 0.85 lie just below a
  // stored level, where the reader applies the most merges on the fly.
  const std::vector<double> ratios = {0.1, 0.25, 0.45, 0.5, 0.7, 0.75, 0.85, 0.9, 0.99};
  for (double ratio : ratios) {
    const uint64_t n = std::min<uint64_t>(tree->merges, std::llround(ratio * mesh.numPoints()));
    double plain, t;
    uint64_t out = 0;
    compare(enc->header, lp, decoded0, *stream_tree, *payload, n, &plain, &t, &out);
    std::printf("%8.2f %10llu %10.4f %10.4f %10.4f %8.1f%%\n", ratio, (unsigned long long)out, plain, t,
                last_tree_decode, 100.0 * t / plain);
  }

  auto levels = buildMipLevels(mesh, *tree, LevelOptions{});
  if (!levels.isOk()) return 1;
  // The reader's path: the finest stored level at or below the ratio, then the remaining merges.
  std::printf("on the fly from the finest stored level at or below the ratio:\n");
  std::printf("%8s %6s %10s %10s %10s %10s %9s\n", "ratio", "level", "tets out", "decode s", "filter s", "tree s",
              "overhead");
  for (double ratio : ratios) {
    const uint64_t n = std::min<uint64_t>(tree->merges, std::llround(ratio * mesh.numPoints()));
    const size_t li = chooseLevel(levels->merges, n);
    const TetMesh& lm = li == 0 ? mesh : levels->meshes[li];
    auto e = encodeLevel(lm, EncodeOptions{});
    if (!e.isOk()) return 1;
    auto tp = encodeMergeTree(*levels->trees[li], e->vertex_order, &lm);
    if (!tp.isOk()) return 1;
    const TetMesh dl = decodedMesh(*e);
    auto st = decodeMergeTree(*tp, lm.numPoints(), d.name, &dl);
    if (!st.isOk()) return 1;
    double plain, t;
    uint64_t out = 0;
    compare(e->header, payloadOf(*e), dl, *st, *tp, n - levels->merges[li], &plain, &t, &out);
    std::printf("%8.2f %6zu %10llu %10.4f %10.4f %10.4f %8.1f%%\n", ratio, li, (unsigned long long)out, plain, t,
                last_tree_decode, 100.0 * t / plain);
  }
  double v0, m0;
  volumeMass(mesh, stats.field, &v0, &m0);
  std::printf("%5s %7s %9s %9s %10s %10s %10s %10s\n", "level", "ratio", "points", "tets", "dVolume%", "dMass%",
              "bytes", "tree bytes");
  uint64_t total = 0, level0 = 0;
  for (size_t i = 0; i < levels->merges.size(); ++i) {
    const TetMesh& lm = i == 0 ? mesh : levels->meshes[i];
    double v, m;
    volumeMass(lm, stats.field, &v, &m);
    auto e = encodeLevel(lm, EncodeOptions{});
    if (!e.isOk()) return 1;
    auto tp = encodeMergeTree(*levels->trees[i], e->vertex_order, &lm);
    if (!tp.isOk()) return 1;
    const uint64_t bytes = levelBytes(*e) + tp->size();
    total += bytes;
    if (i == 0) level0 = bytes;
    std::printf("%5zu %7.4f %9zu %9zu %10.4f %10.4f %10llu %10zu\n", i, levels->ratios[i], lm.numPoints(), lm.numTets(),
                100.0 * (v - v0) / v0, m0 != 0 ? 100.0 * (m - m0) / std::fabs(m0) : 0.0, (unsigned long long)bytes,
                tp->size());
  }
  std::printf("all levels: %llu bytes = %.2f x level 0\n", (unsigned long long)total, double(total) / level0);
  // What `gtn convert` stores by default: the levels within the storage bound, counted in the file.
  GtnWriteOptions wo;
  wo.level_storage_limit = 2.0;
  const std::string path = "/tmp/gtn-bench-simplify-" + d.name + ".gtn";
  if (!writeGtnFile(path, levels->inputs(mesh), wo).isOk()) return 1;
  auto reader = GtnReader::open(path);
  if (!reader.isOk()) return 1;
  uint64_t file_total = 0;
  for (size_t i = 0; i < (*reader)->levels(); ++i) file_total += (*reader)->level(i).bytes;
  std::printf("stored by default (bound 2 x level 0): levels 0..%zu, %llu bytes = %.3f x level 0 (file: %llu bytes)\n",
              (*reader)->levels() - 1, (unsigned long long)file_total, double(file_total) / (*reader)->level(0).bytes,
              (unsigned long long)(*reader)->file().bytes);
  std::remove(path.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string data = GTN_DEFAULT_DATA_DIR;
  if (const char* env = std::getenv("GTN_DATA_DIR")) data = env;
  int repeat = 5;
  std::vector<std::string> names;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--data" && i + 1 < argc) {
      data = argv[++i];
    } else if (a == "--repeat" && i + 1 < argc) {
      repeat = std::max(1, std::atoi(argv[++i]));
    } else {
      names.push_back(a);
    }
  }
  const std::vector<Dataset> all = {
      {"spx", {data + "/vtk/spx.vtk"}, 6},
      {"cornell", {data + "/tetgen/cornell_spheres.1.ele"}, 6},
      {"bluntfin", {data + "/plot3d/bluntfinxyz.bin", data + "/plot3d/bluntfinq.bin"}, 6},
      {"combustion", {data + "/plot3d/combxyz.bin", data + "/plot3d/combq.bin"}, 6},
      {"bluntfin5", {data + "/plot3d/bluntfinxyz.bin", data + "/plot3d/bluntfinq.bin"}, 5},
      {"combustion5", {data + "/plot3d/combxyz.bin", data + "/plot3d/combq.bin"}, 5},
  };
  int rc = 0;
  for (const Dataset& d : all) {
    if (!names.empty() && std::find(names.begin(), names.end(), d.name) == names.end()) continue;
    rc |= run(d, repeat);
  }
  return rc;
}
