// bench-pieces: a level cut into pieces (codec/pieces.h) against the same level as one piece: bytes
// (the pieces' streams, the seam classes, the tables), the seam vertices, and encode and decode wall
// time with 1 thread and with every thread, rounds interleaved.
//   bench-pieces [--piece-tets N,N,...] [--rounds R] [--split 5|6] INPUT [INPUT...]
// INPUT: what `gtn convert` imports (several files for PLOT3D's xyz and q).
#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "codec/pieces.h"
#include "codec/pieces_check.h"
#include "convert/import.h"

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

uint64_t bytesOf(const gtn::PiecedLevel& level) {
  uint64_t n = 0;
  for (const gtn::EncodedLevel& e : level.encoded) {
    n += e.boundary.size() + e.connectivity.size() + e.geometry.size();
    for (const auto& s : e.point_fields) n += s.size();
    for (const auto& s : e.cell_fields) n += s.size();
  }
  for (const auto& s : level.seam_streams) n += s.size();
  // The level header's piece table and the seam table (varints and boxes), as the container stores them.
  if (level.pieces.size() > 1) n += level.pieces.size() * (1 + 5 * 4 + 48) + level.classes.size() * 8;
  return n;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<uint64_t> sizes = {uint64_t{1} << 30, gtn::kDefaultPieceTets, uint64_t{1} << 16};
  int rounds = 3;
  gtn::ImportOptions options;
  std::vector<std::string> inputs;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--piece-tets" && i + 1 < argc) {
      sizes = {uint64_t{1} << 30};
      std::string list = argv[++i];
      for (size_t p = 0; p < list.size();) {
        const size_t q = list.find(',', p);
        sizes.push_back(std::strtoull(list.substr(p, q - p).c_str(), nullptr, 10));
        p = q == std::string::npos ? list.size() : q + 1;
      }
    } else if (a == "--rounds" && i + 1 < argc) {
      rounds = std::max(1, std::atoi(argv[++i]));
    } else if (a == "--split" && i + 1 < argc) {
      options.split = std::atoi(argv[++i]);
    } else {
      inputs.push_back(a);
    }
  }
  if (inputs.empty()) {
    std::fprintf(stderr, "usage: bench-pieces [--piece-tets N,N,...] [--rounds R] [--split 5|6] INPUT...\n");
    return 2;
  }
  gtn::StatusOr<gtn::ImportResult> imported = gtn::importMesh(inputs, options);
  if (!imported.isOk()) {
    std::fprintf(stderr, "bench-pieces: %s\n", imported.status().message().c_str());
    return 1;
  }
  const gtn::TetMesh& mesh = imported->mesh;
  const int all = tbb::info::default_concurrency();
  std::printf("%s: %zu points, %zu tetrahedra; %d rounds, medians of wall seconds; threads 1 and %d\n",
              inputs[0].c_str(), mesh.numPoints(), mesh.numTets(), rounds, all);
  std::printf(
      "| piece tets | pieces | classes | seam vertices | bytes | vs one piece | encode 1t | encode %dt | decode 1t | "
      "decode %dt | decode speed-up |\n",
      all, all);
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
  uint64_t one_piece = 0;
  for (uint64_t size : sizes) {
    std::vector<double> enc1, encn, dec1, decn;
    gtn::PiecedLevel level;
    for (int r = 0; r < rounds; ++r) {
      for (int threads : {1, all}) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        double t0 = now();
        gtn::StatusOr<gtn::PiecedLevel> e = gtn::encodePieces(mesh, {}, size);
        const double te = now() - t0;
        if (!e.isOk()) {
          std::fprintf(stderr, "bench-pieces: %s\n", e.status().message().c_str());
          return 1;
        }
        level = std::move(*e);
        const gtn::PiecedLevelView view = gtn::piecedViewOf(level);
        t0 = now();
        gtn::StatusOr<gtn::DecodedPieces> d = gtn::decodePieces(view, {}, "bench");
        const double td = now() - t0;
        if (!d.isOk() || d->mesh.numTets() != mesh.numTets()) {
          std::fprintf(stderr, "bench-pieces: decode failed: %s\n", d.isOk() ? "counts" : d.status().message().c_str());
          return 1;
        }
        (threads == 1 ? enc1 : encn).push_back(te);
        (threads == 1 ? dec1 : decn).push_back(td);
        if (all == 1) break;
      }
    }
    uint64_t seam = 0, seam_bytes = 0, conn = 0, bnd = 0, geo = 0, pf = 0, cf = 0;
    for (const gtn::EncodedLevel& e : level.encoded) {
      bnd += e.boundary.size();
      geo += e.geometry.size();
      for (const auto& s : e.point_fields) pf += s.size();
      for (const auto& s : e.cell_fields) cf += s.size();
    }
    std::fprintf(stderr, "streams: boundary %llu, geometry %llu, point fields %llu, cell fields %llu\n",
                 (unsigned long long)bnd, (unsigned long long)geo, (unsigned long long)pf, (unsigned long long)cf);
    for (const gtn::SeamClass& c : level.classes) seam += c.points;
    for (const auto& s : level.seam_streams) seam_bytes += s.size();
    for (const gtn::EncodedLevel& e : level.encoded) conn += e.boundary.size() + e.connectivity.size();
    std::fprintf(stderr, "seam streams %llu bytes (%.1f bits per seam vertex), boundary+connectivity %llu bytes\n",
                 static_cast<unsigned long long>(seam_bytes), 8.0 * seam_bytes / std::max<uint64_t>(1, seam),
                 static_cast<unsigned long long>(conn));
    const uint64_t bytes = bytesOf(level);
    if (one_piece == 0) one_piece = bytes;
    const double d1 = median(dec1), dn = median(decn.empty() ? dec1 : decn);
    std::printf("| %llu | %zu | %zu | %llu (%.1f%%) | %llu | %+.2f%% | %.2f | %.2f | %.3f | %.3f | %.2f |\n",
                static_cast<unsigned long long>(std::min<uint64_t>(size, mesh.numTets())), level.pieces.size(),
                level.classes.size(), static_cast<unsigned long long>(seam), 100.0 * seam / mesh.numPoints(),
                static_cast<unsigned long long>(bytes), 100.0 * (double(bytes) / one_piece - 1.0), median(enc1),
                median(encn.empty() ? enc1 : encn), d1, dn, d1 / dn);
    std::fflush(stdout);
  }
  return 0;
}
