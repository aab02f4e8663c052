// bench-grid: the structured-piece coder (codec/grid_coder.h) on the PLOT3D datasets: bits per
// tetrahedron in all and per stream, the predictor and form each component took, the same with one
// predictor forced on every component, and the decode speed (best of several runs, one thread).
//
//   bench-grid [data_dir] [--split 5|6] [--runs N]
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "codec/grid_coder.h"
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
  for (int a = 0; a < 3; ++a) dims[a] = (uint32_t{b[4 * a]} << 24) | (uint32_t{b[4 * a + 1]} << 16) | (uint32_t{b[4 * a + 2]} << 8) | b[4 * a + 3];
  return ok;
}

double bits(size_t bytes, size_t tets) { return 8.0 * static_cast<double>(bytes) / static_cast<double>(tets); }

}  // namespace

int main(int argc, char** argv) {
  std::string dir = GTN_DEFAULT_DATA_DIR;
  int split = 5, runs = 10;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--split" && i + 1 < argc) split = std::atoi(argv[++i]);
    else if (a == "--runs" && i + 1 < argc) runs = std::atoi(argv[++i]);
    else dir = a;
  }
  const struct {
    const char* name;
    const char* xyz;
    const char* q;
  } sets[] = {{"bluntfin", "plot3d/bluntfinxyz.bin", "plot3d/bluntfinq.bin"}, {"combustion", "plot3d/combxyz.bin", "plot3d/combq.bin"}};
  int status = 0;
  for (const auto& s : sets) {
    ImportOptions options;
    options.split = split;
    const std::string xyz = dir + "/" + s.xyz, q = dir + "/" + s.q;
    auto imported = importPlot3d({xyz, q}, options);
    uint32_t dims[3];
    if (!imported.isOk() || !plot3dDims(xyz, dims)) {
      std::fprintf(stderr, "%s: %s\n", s.name, imported.isOk() ? "cannot read its dimensions" : imported.status().message().c_str());
      status = 1;
      continue;
    }
    const TetMesh& mesh = imported->mesh;
    auto layout = matchGridLayout(mesh, dims);
    if (!layout.isOk()) {
      std::fprintf(stderr, "%s: %s\n", s.name, layout.status().message().c_str());
      status = 1;
      continue;
    }
    const size_t T = mesh.numTets();
    std::printf("%s /%d: %u x %u x %u nodes, %zu tetrahedra, %zu exceptions, %llu extra points\n", s.name, split, dims[0], dims[1],
                dims[2], T, layout->exceptions.size(), static_cast<unsigned long long>(layout->extras()));
    for (int forced = -1; forced <= 2; ++forced) {
      GridEncodeOptions eo;
      eo.predictor = forced;
      GridEncodeReport r;
      auto piece = encodeGridPiece(*layout, mesh, eo, &r);
      if (!piece.isOk()) {
        std::fprintf(stderr, "%s: %s\n", s.name, piece.status().message().c_str());
        status = 1;
        break;
      }
      const char* label = forced < 0 ? "measured" : forced == 0 ? "all Lorenzo" : forced == 1 ? "all previous-i" : "all linear-i";
      std::printf("  %-15s total %7.3f bits/tet (%zu bytes): header %.4f, EXCP %.4f, GEOM %.3f", label, bits(piece->size(), T),
                  piece->size(), bits(r.header, T), bits(r.excp, T), bits(r.geom, T));
      for (size_t f = 0; f < r.point_fields.size(); ++f) std::printf(", %s %.3f", mesh.point_fields[f].name.c_str(), bits(r.point_fields[f], T));
      std::printf("\n");
      if (forced < 0) {
        std::printf("  components (predictor: 0 Lorenzo, 1 previous i, 2 linear i; form):");
        for (size_t c = 0; c < r.predictors.size(); ++c) std::printf(" [%d %s]", r.predictors[c], r.forms[c].c_str());
        std::printf("\n");
        const GridSchema schema = gridSchemaOf(mesh);
        double best = 1e300;
        for (int run = 0; run < runs; ++run) {
          const auto t0 = std::chrono::steady_clock::now();
          auto back = decodeGridPiece(*piece, schema, s.name);
          const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          if (!back.isOk() || back->mesh.tets != mesh.tets) {
            std::fprintf(stderr, "%s: the decode differs: %s\n", s.name, back.isOk() ? "tetrahedra" : back.status().message().c_str());
            status = 1;
            break;
          }
          best = std::min(best, sec);
        }
        std::printf("  decode: %.2f ms, %.1f million tetrahedra per second (one thread, best of %d)\n", best * 1e3, T / best / 1e6, runs);
      }
    }
  }
  return status;
}
