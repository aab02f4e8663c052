// bench-grid: the structured-piece coder (codec/grid_coder.h) on the PLOT3D datasets: bits per
// tetrahedron in all and per stream, the predictor and form each component took, the same with one
// predictor forced on every component, and the decode speed (best of several runs, one thread); then
// the level as a structured piece (codec/structured_piece.h, the importer's block): its bits per
// tetrahedron and its decode with the mesh stream's events into TetMeshBuilder.
//
//   bench-grid [data_dir] [--split 5|6] [--runs N] [--piece-only]
// (--piece-only: the structured piece's size and decode alone)
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include "codec/grid_coder.h"
#include "codec/structured_piece.h"
#include "convert/import.h"
#include "format/file_io.h"

using namespace gtn;

namespace {

bool plot3dDims(const std::string& path, uint32_t dims[3]) {
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  unsigned char b[12];
  const bool ok = std::fread(b, 1, 12, f) == 12;
  std::fclose(f);
  for (int a = 0; a < 3; ++a)
    dims[a] =
        (uint32_t{b[4 * a]} << 24) | (uint32_t{b[4 * a + 1]} << 16) | (uint32_t{b[4 * a + 2]} << 8) | b[4 * a + 3];
  return ok;
}

// This thread's CPU time in seconds: the machine may be shared, and wall time then counts others' work.
double threadSeconds() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double bits(size_t bytes, size_t tets) { return 8.0 * static_cast<double>(bytes) / static_cast<double>(tets); }

}  // namespace

int main(int argc, char** argv) {
  std::string dir = GTN_DEFAULT_DATA_DIR;
  int split = 5, runs = 10;
  bool piece_only = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--split" && i + 1 < argc) split = std::atoi(argv[++i]);
    else if (a == "--runs" && i + 1 < argc) runs = std::atoi(argv[++i]);
    else if (a == "--piece-only") piece_only = true;
    else dir = a;
  }
  const struct {
    const char* name;
    const char* xyz;
    const char* q;
  } sets[] = {{"bluntfin", "plot3d/bluntfinxyz.bin", "plot3d/bluntfinq.bin"},
              {"combustion", "plot3d/combxyz.bin", "plot3d/combq.bin"}};
  int status = 0;
  for (const auto& s : sets) {
    ImportOptions options;
    options.split = split;
    const std::string xyz = dir + "/" + s.xyz, q = dir + "/" + s.q;
    auto imported = importPlot3d({xyz, q}, options);
    uint32_t dims[3];
    if (!imported.isOk() || !plot3dDims(xyz, dims)) {
      std::fprintf(stderr, "%s: %s\n", s.name,
                   imported.isOk() ? "cannot read its dimensions" : imported.status().message().c_str());
      status = 1;
      continue;
    }
    const TetMesh& mesh = imported->mesh;
    auto layout = matchGridLayout(mesh, dims);
    if (layout.isOk()) {
      // The level as a structured piece, decoded into TetMeshBuilder (every event of the mesh stream).
      if (mesh.blocks.size() != 1) {
        std::fprintf(stderr, "%s: the importer offers no block\n", s.name);
        status = 1;
        continue;
      }
      const double e0 = threadSeconds();
      auto level = encodeStructuredPiece(mesh, mesh.blocks[0]);
      const double encode_cpu = threadSeconds() - e0;
      const double m0 = threadSeconds();
      const bool matched = matchGridLayout(mesh, mesh.blocks[0].dims, mesh.blocks[0].aliases).isOk();
      const double match_cpu = threadSeconds() - m0;
      if (!level.isOk()) {
        std::fprintf(stderr, "%s: %s\n", s.name, level.status().message().c_str());
        status = 1;
        continue;
      }
      double best = 1e300, best_cpu = 1e300;
      for (int run = 0; run < runs; ++run) {
        TetMeshBuilder builder;
        const auto t0 = std::chrono::steady_clock::now();
        const double c0 = threadSeconds();
        const Status st = decodeStructuredPiece(level->header, level->connectivity, builder, s.name);
        best_cpu = std::min(best_cpu, threadSeconds() - c0);
        best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        if (!st.isOk() || builder.mesh().tets != mesh.tets || builder.mesh().coords != mesh.coords) {
          std::fprintf(stderr, "%s: the structured piece decodes wrong: %s\n", s.name,
                       st.isOk() ? "tetrahedra or coordinates differ" : st.message().c_str());
          status = 1;
          break;
        }
      }
      // The same into a sink that only counts (the decoder's own part).
      double count_cpu = 1e300;
      for (int run = 0; run < runs; ++run) {
        CountingSink counter;
        const double c0 = threadSeconds();
        const Status st = decodeStructuredPiece(level->header, level->connectivity, counter, s.name);
        count_cpu = std::min(count_cpu, threadSeconds() - c0);
        if (!st.isOk() || counter.tets != mesh.numTets()) status = 1;
      }
      const size_t T = mesh.numTets();
      std::printf(
          "%s /%d as a structured piece: %.3f bits/tet (%zu bytes), %llu boundary triangles; decode into "
          "TetMeshBuilder: %.2f ms wall, %.2f ms thread CPU: %.1f (wall), %.1f (CPU) million tetrahedra per second; "
          "into a counting sink %.1f (CPU) (best of %d); encode %.0f ms CPU, of which matching the block %.1f ms%s\n",
          s.name, split, bits(level->connectivity.size(), T), level->connectivity.size(),
          static_cast<unsigned long long>(level->header.boundary_triangles), best * 1e3, best_cpu * 1e3, T / best / 1e6,
          T / best_cpu / 1e6, T / count_cpu / 1e6, runs, encode_cpu * 1e3, match_cpu * 1e3,
          matched ? "" : " (no match)");
    }
    if (!layout.isOk()) {
      std::fprintf(stderr, "%s: %s\n", s.name, layout.status().message().c_str());
      status = 1;
      continue;
    }
    const size_t T = mesh.numTets();
    std::printf("%s /%d: %u x %u x %u nodes, %zu tetrahedra, %zu exceptions, %llu extra points\n", s.name, split,
                dims[0], dims[1], dims[2], T, layout->exceptions.size(),
                static_cast<unsigned long long>(layout->extras()));
    // Runs: the default (predictors and forms by measurement), each predictor forced, each value
    // stream form forced.
    const struct {
      const char* label;
      int predictor, value_form;
      bool timed;
    } configs[] = {{"default", -1, -1, true},      {"all Lorenzo", 0, -1, false}, {"all previous-i", 1, -1, false},
                   {"all linear-i", 2, -1, false}, {"all form 0", -1, 0, true},   {"all form 1", -1, 1, true}};
    for (const auto& config : configs) {
      if (piece_only) break;
      GridEncodeOptions eo;
      eo.predictor = config.predictor;
      eo.value_form = config.value_form;
      GridEncodeReport r;
      auto piece = encodeGridPiece(*layout, mesh, eo, &r);
      if (!piece.isOk()) {
        std::fprintf(stderr, "%s: %s\n", s.name, piece.status().message().c_str());
        status = 1;
        break;
      }
      const char* label = config.label;
      std::printf("  %-15s total %7.3f bits/tet (%zu bytes): header %.4f, EXCP %.4f, GEOM %.3f", label,
                  bits(piece->size(), T), piece->size(), bits(r.header, T), bits(r.excp, T), bits(r.geom, T));
      for (size_t f = 0; f < r.point_fields.size(); ++f)
        std::printf(", %s %.3f", mesh.point_fields[f].name.c_str(), bits(r.point_fields[f], T));
      std::printf("; stream forms (GEOM, PFLD...):");
      for (uint8_t f : r.stream_forms) std::printf(" %d", f);
      std::printf("\n");
      if (config.predictor < 0 && config.value_form < 0) {
        std::printf("  components (predictor: 0 Lorenzo, 1 previous i, 2 linear i; form):");
        for (size_t c = 0; c < r.predictors.size(); ++c) std::printf(" [%d %s]", r.predictors[c], r.forms[c].c_str());
        std::printf("\n");
      }
      if (config.timed) {
        const GridSchema schema = gridSchemaOf(mesh);
        double best = 1e300, best_cpu = 1e300;
        for (int run = 0; run < runs; ++run) {
          const auto t0 = std::chrono::steady_clock::now();
          const double c0 = threadSeconds();
          auto back = decodeGridPiece(*piece, schema, s.name);
          best_cpu = std::min(best_cpu, threadSeconds() - c0);
          const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          bool same = back.isOk() && back->mesh.tets == mesh.tets && back->mesh.coords == mesh.coords &&
                      back->mesh.point_fields.size() == mesh.point_fields.size();
          for (size_t f = 0; same && f < mesh.point_fields.size(); ++f)
            same = back->mesh.point_fields[f].bytes == mesh.point_fields[f].bytes;
          if (!same) {
            std::fprintf(stderr, "%s: the decode differs: %s\n", s.name,
                         back.isOk() ? "tetrahedra or values" : back.status().message().c_str());
            status = 1;
            break;
          }
          best = std::min(best, sec);
        }
        std::printf(
            "  decode: %.2f ms wall, %.2f ms thread CPU time: %.1f (wall), %.1f (CPU) million tetrahedra per second on "
            "one core (best of %d)\n",
            best * 1e3, best_cpu * 1e3, T / best / 1e6, T / best_cpu / 1e6, runs);
      }
    }
  }
  return status;
}
