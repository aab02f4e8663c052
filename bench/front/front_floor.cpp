// bench-front: what the peeling front's bookkeeping alone costs, against the whole decoder.
//
//   build/bench-front [DATA_DIR [DATASET_SUBSTRING]]
//
// For each dataset of the shared data directory the level is encoded, then decoded (the fastest of
// several runs, thread CPU time, into a sink that only counts: the decoder's own rate, as
// bench-compression's "dec" column). One more decode gives the tetrahedra in stream order over
// slots (reused last-freed-first, as the decoder's pool is), and the front's bookkeeping is
// replayed from them with the decoder's own containers (codec/flat_maps.h): per tetrahedron, its four faces looked up by sorted key, each open one closed
// (erased with its three edges) and each other one opened (inserted, its edges put, its key queued),
// and one queued key taken. No symbol is decoded, no candidate gathered, no value predicted. Two
// replays: the face map, the edge map and the queue together (what the decoder keeps), and the
// face map alone (the least that any surface-peeling decoder keeps: it must know which faces a
// tetrahedron closes).
//
// The figures bound what the format's connectivity design allows: a decoder cannot be faster than
// its bookkeeping. The goal is 5 million tetrahedra per second (200 ns a tetrahedron), geometry
// and fields included.
#include <algorithm>
#include <array>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "codec/flat_maps.h"
#include "codec/level_codec.h"
#include "convert/import.h"
#include "mesh/faces.h"
#include "mesh/index.h"

namespace {

using gtn::bench::threadSeconds;

// The decoded tetrahedra, in stream order, over slots instead of vertex ids: a vertex takes the
// last freed slot, or a new one, and frees it when the stream retires it.
struct SlotSink : gtn::MeshSink {
  std::vector<std::array<uint32_t, 4>> tets;
  uint32_t pool = 0;  // slots ever used
  gtn::Status beginLevel(const gtn::LevelHeader& h) override {
    slot_.assign(h.points, 0);
    return gtn::Status::ok();
  }
  gtn::Status vertex(uint32_t id, const double*, const uint8_t*) override {
    uint32_t s = pool;
    if (free_.empty()) {
      ++pool;
    } else {
      s = free_.back();
      free_.pop_back();
    }
    slot_[id] = s;
    return gtn::Status::ok();
  }
  gtn::Status boundaryTriangle(const uint32_t*) override { return gtn::Status::ok(); }
  gtn::Status endBoundary() override { return gtn::Status::ok(); }
  gtn::Status tet(const uint32_t* v, const uint8_t*) override {
    tets.push_back({slot_[v[0]], slot_[v[1]], slot_[v[2]], slot_[v[3]]});
    return gtn::Status::ok();
  }
  gtn::Status retireVertex(uint32_t id) override {
    free_.push_back(slot_[id]);
    return gtn::Status::ok();
  }
  gtn::Status endLevel() override { return gtn::Status::ok(); }

 private:
  std::vector<uint32_t> slot_, free_;
};

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
      const uint32_t f[3] = {e[gtn::kTetFace[k][0]], e[gtn::kTetFace[k][1]], e[gtn::kTetFace[k][2]]};
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
        g.cell = gtn::kNoIndex;
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

}  // namespace

int main(int argc, char** argv) {
  const std::string dir = gtn::bench::dataDir(argc > 1 ? argv[1] : nullptr, GTN_DEFAULT_DATA_DIR);
  const std::string filter = argc > 2 ? argv[2] : "";
  std::printf("ns per tetrahedron (thread CPU time, fastest run); Mt/s = million tetrahedra per second\n");
  std::printf("%-16s %8s | %8s %6s | %10s %6s %6s | %10s %6s %6s\n", "dataset", "tets", "decode", "Mt/s", "faces+edg",
              "Mt/s", "share", "faces", "Mt/s", "share");
  int status = 0;
  for (const gtn::bench::Dataset& ds : gtn::bench::sharedDatasets(dir)) {
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
    SlotSink slots;
    if (const gtn::Status st = gtn::decodeLevel(enc->header, pl, slots, nullptr, ds.name); !st.isOk()) {
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
    const auto& tets = slots.tets;
    size_t closed_all = 0, closed_faces = 0;
    const double both = fastest(5, [&] { return replay<true>(tets, slots.pool, &closed_all); });
    const double faces = fastest(5, [&] { return replay<false>(tets, slots.pool, &closed_faces); });
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
    std::printf("%-16s %8zu | %8.0f %6.2f | %10.0f %6.2f %5.0f%% | %10.0f %6.2f %5.0f%%\n", ds.name.c_str(),
                tets.size(), 1e9 * dec / nt, nt / dec / 1e6, 1e9 * both / nt, nt / both / 1e6, 100 * both / dec,
                1e9 * faces / nt, nt / faces / 1e6, 100 * faces / dec);
    std::fflush(stdout);
  }
  return status;
}
