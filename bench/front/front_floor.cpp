// bench-front: what the peeling front's bookkeeping alone costs, against the whole decoder.
//
//   build/bench-front [DATA_DIR [DATASET_SUBSTRING]]
//
// For each dataset the level is encoded, then decoded (the fastest of several runs, thread CPU time,
// into a sink that only counts: the decoder's own rate, as bench-compression's "dec" column). The
// decode's events are recorded once, and the front's bookkeeping is replayed from them with the
// decoder's own containers (codec/flat_maps.h), vertices in slots reused last-freed-first as the
// decoder's pool does: per tetrahedron, its four faces looked up by sorted key, each open one closed
// (erased with its three edges) and each other one opened (inserted, its edges put, its key queued),
// and one queued key taken. No symbol is decoded, no candidate gathered, no value predicted. Two
// replays: the face map, the edge map and the queue together (what the decoder keeps), and the
// face map alone (the least that any surface-peeling decoder keeps: it must know which faces a
// tetrahedron closes).
//
// The figures bound what the format's connectivity design allows: a decoder cannot be faster than
// its bookkeeping. Issue 4 asks for 5 million tetrahedra per second (200 ns a tetrahedron), geometry
// and fields included.
#include <time.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "codec/flat_maps.h"
#include "codec/level_codec.h"
#include "convert/import.h"

namespace {

double threadSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// The decode's events as the replay needs them: +1 + id for a vertex, -1 - id for its retirement,
// and each tetrahedron as its four ids (kTet marks one in `events`, its ids in `tets`).
struct Recording : gtn::MeshSink {
  static constexpr int64_t kTet = INT64_MIN;
  std::vector<int64_t> events;
  std::vector<std::array<uint32_t, 4>> tets;
  gtn::Status beginLevel(const gtn::LevelHeader&) override { return gtn::Status::ok(); }
  gtn::Status vertex(uint32_t id, const double*, const uint8_t*) override {
    events.push_back(1 + int64_t{id});
    return gtn::Status::ok();
  }
  gtn::Status boundaryTriangle(const uint32_t*) override { return gtn::Status::ok(); }
  gtn::Status endBoundary() override { return gtn::Status::ok(); }
  gtn::Status tet(const uint32_t* v, const uint8_t*) override {
    events.push_back(kTet);
    tets.push_back({v[0], v[1], v[2], v[3]});
    return gtn::Status::ok();
  }
  gtn::Status retireVertex(uint32_t id) override {
    events.push_back(-1 - int64_t{id});
    return gtn::Status::ok();
  }
  gtn::Status endLevel() override { return gtn::Status::ok(); }
};

// The recording with every vertex id replaced by its slot (a pool that reuses the last freed slot
// first, as the decoder's does): the tetrahedra in order, over slots.
std::vector<std::array<uint32_t, 4>> slotTets(const Recording& r, size_t points, uint32_t* pool) {
  std::vector<uint32_t> slot(points, 0), free;
  std::vector<std::array<uint32_t, 4>> out;
  out.reserve(r.tets.size());
  uint32_t next = 0;
  size_t t = 0;
  for (const int64_t e : r.events) {
    if (e == Recording::kTet) {
      const auto& v = r.tets[t++];
      out.push_back({slot[v[0]], slot[v[1]], slot[v[2]], slot[v[3]]});
    } else if (e > 0) {
      uint32_t s = next;
      if (!free.empty()) {
        s = free.back();
        free.pop_back();
      } else {
        ++next;
      }
      slot[static_cast<size_t>(e - 1)] = s;
    } else {
      free.push_back(slot[static_cast<size_t>(-1 - e)]);
    }
  }
  *pool = next;
  return out;
}

// A tetrahedron's faces, each with its vertices in the order that keeps the fourth vertex behind it
// (the codec's kTetFace).
constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

// One replay of the bookkeeping; returns its thread CPU seconds. `closed`: faces found open.
template <bool kEdges>
double replay(const std::vector<std::array<uint32_t, 4>>& tets, uint32_t pool, size_t* closed) {
  gtn::FaceMap faces;
  gtn::EdgeMap edges;
  gtn::RingQueue<std::array<uint32_t, 3>> queue;
  faces.reserveSlots(pool);
  size_t found = 0;
  const double t0 = threadSeconds();
  for (const auto& e : tets) {
    if (!queue.empty()) queue.pop_front();
    for (int k = 0; k < 4; ++k) {
      const uint32_t f[3] = {e[kFace[k][0]], e[kFace[k][1]], e[kFace[k][2]]};
      uint32_t key[3];
      gtn::FaceMap::sortedKey(f, key);
      const long at = faces.find(key);
      if (at >= 0) {
        ++found;
        const gtn::FrontFace g = faces.at(at);
        faces.eraseAt(at);
        if constexpr (kEdges)
          for (int j = 0; j < 3; ++j) edges.eraseIf(g.v[j], g.v[(j + 1) % 3], g.v[(j + 2) % 3]);
      } else {
        gtn::FrontFace g{};
        for (int j = 0; j < 3; ++j) g.v[j] = f[j];
        g.d = e[k];
        g.cell = ~0u;
        faces.insert(g);
        if constexpr (kEdges) {
          for (int j = 0; j < 3; ++j) edges.put(f[j], f[(j + 1) % 3], f[(j + 2) % 3]);
          queue.push_back({key[0], key[1], key[2]});
        }
      }
    }
  }
  const double s = threadSeconds() - t0;
  *closed = found;
  return s;
}

// The fastest of at least `runs` calls of f, and of as many more as fit in about 0.4 s.
template <class F>
double fastest(int runs, F f) {
  double best = 1e300, spent = 0;
  for (int i = 0; i < 100 && (i < runs || spent < 0.4); ++i) {
    const double s = f();
    best = std::min(best, s);
    spent += s;
  }
  return best;
}

struct Dataset {
  std::string name;
  std::vector<std::string> inputs;
  int split = 6;
};

}  // namespace

int main(int argc, char** argv) {
  std::string dir = argc > 1 ? argv[1] : "";
  if (dir.empty()) {
    const char* env = std::getenv("GTN_DATA_DIR");
    dir = env && *env ? env : GTN_DEFAULT_DATA_DIR;
  }
  const std::string filter = argc > 2 ? argv[2] : "";
  const std::filesystem::path d(dir);
  const std::vector<Dataset> all = {
      {"bluntfin/5", {(d / "plot3d/bluntfinxyz.bin").string(), (d / "plot3d/bluntfinq.bin").string()}, 5},
      {"bluntfin/6", {(d / "plot3d/bluntfinxyz.bin").string(), (d / "plot3d/bluntfinq.bin").string()}, 6},
      {"combustion/5", {(d / "plot3d/combxyz.bin").string(), (d / "plot3d/combq.bin").string()}, 5},
      {"combustion/6", {(d / "plot3d/combxyz.bin").string(), (d / "plot3d/combq.bin").string()}, 6},
      {"spx", {(d / "vtk/spx.vtk").string()}},
      {"bunny", {(d / "medit/bunny.mesh").string()}},
      {"cornell_spheres", {(d / "tetgen/cornell_spheres.1.ele").string()}},
  };
  std::printf("ns per tetrahedron (thread CPU time, fastest run); Mt/s = million tetrahedra per second\n");
  std::printf("%-16s %8s | %8s %6s | %10s %6s %6s | %10s %6s %6s\n", "dataset", "tets", "decode", "Mt/s",
              "faces+edg", "Mt/s", "share", "faces", "Mt/s", "share");
  int status = 0;
  for (const Dataset& ds : all) {
    if (!filter.empty() && ds.name.find(filter) == std::string::npos) continue;
    gtn::ImportOptions io;
    io.split = ds.split;
    auto imported = gtn::importMesh(ds.inputs, io);
    if (!imported.isOk()) {
      std::printf("%-16s import failed: %s\n", ds.name.c_str(), imported.status().message().c_str());
      status = 1;
      continue;
    }
    const gtn::TetMesh& m = imported->mesh;
    auto enc = gtn::encodeLevel(m, gtn::EncodeOptions{});
    if (!enc.isOk()) {
      std::printf("%-16s encode failed: %s\n", ds.name.c_str(), enc.status().message().c_str());
      status = 1;
      continue;
    }
    const gtn::LevelPayload pl = gtn::payloadOf(*enc);
    Recording rec;
    if (const gtn::Status st = gtn::decodeLevel(enc->header, pl, rec, nullptr, ds.name); !st.isOk()) {
      std::printf("%-16s decode failed: %s\n", ds.name.c_str(), st.message().c_str());
      status = 1;
      continue;
    }
    bool ok = true;
    const double dec = fastest(5, [&] {
      gtn::CountingSink sink;
      const double t0 = threadSeconds();
      ok &= gtn::decodeLevel(enc->header, pl, sink, nullptr, ds.name).isOk();
      return threadSeconds() - t0;
    });
    uint32_t pool = 0;
    const auto tets = slotTets(rec, m.numPoints(), &pool);
    size_t closed_all = 0, closed_faces = 0;
    const double both = fastest(5, [&] { return replay<true>(tets, pool, &closed_all); });
    const double faces = fastest(5, [&] { return replay<false>(tets, pool, &closed_faces); });
    // Every interior face is closed once, by the second of its two tetrahedra.
    const size_t interior = (4 * tets.size() - enc->header.boundary_triangles) / 2;
    if (!ok) {
      std::printf("%-16s a timed decode failed\n", ds.name.c_str());
      status = 1;
      continue;
    }
    if (closed_all != interior || closed_faces != interior) {
      std::printf("%-16s replay disagrees: %zu and %zu faces closed, %zu interior\n", ds.name.c_str(), closed_all,
                  closed_faces, interior);
      status = 1;
      continue;
    }
    const double nt = static_cast<double>(tets.size());
    std::printf("%-16s %8zu | %8.0f %6.2f | %10.0f %6.2f %5.0f%% | %10.0f %6.2f %5.0f%%\n", ds.name.c_str(), tets.size(),
                1e9 * dec / nt, nt / dec / 1e6, 1e9 * both / nt, nt / both / 1e6, 100 * both / dec, 1e9 * faces / nt,
                nt / faces / 1e6, 100 * faces / dec);
    std::fflush(stdout);
  }
  return status;
}
