// bench-decode: how fast a .gtn file's level opens, in-process: the level decoded into a TetMesh
// (points, tetrahedra, every field), as a program that loads the mesh would.
//
//   build/bench-decode [--level I] [--reps N] FILE.gtn...
//
// The file is read into memory once; each repetition decodes the level from memory (the chunks'
// checksums, the streams' decoding, the mesh's assembly). Prints per file the tetrahedra, the fastest
// and the median repetition in milliseconds of this thread's CPU time, and nanoseconds per
// tetrahedron at the median. Comparing two builds: run them alternately, several times, on the same
// files (the machine's speed wanders from one minute to the next).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "format/gtn_reader.h"
#include "mesh/mesh_stream.h"

int main(int argc, char** argv) {
  size_t level = 0;
  int reps = 5;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--level" && i + 1 < argc) {
      level = std::strtoul(argv[++i], nullptr, 10);
    } else if (a == "--reps" && i + 1 < argc) {
      reps = std::max(1, std::atoi(argv[++i]));
    } else {
      files.push_back(a);
    }
  }
  if (files.empty()) {
    std::fprintf(stderr, "usage: bench-decode [--level I] [--reps N] FILE.gtn...\n");
    return 2;
  }
  for (const std::string& path : files) {
    std::ifstream in(path, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in.good() && !in.eof()) {
      std::fprintf(stderr, "bench-decode: %s: cannot read\n", path.c_str());
      return 1;
    }
    std::vector<double> ms;
    size_t tets = 0;
    for (int r = 0; r < reps; ++r) {
      const double t0 = gtn::bench::threadSeconds();
      auto reader = gtn::GtnReader::openMemory(bytes, path);
      if (!reader.isOk()) {
        std::fprintf(stderr, "bench-decode: %s\n", reader.status().message().c_str());
        return 1;
      }
      gtn::TetMeshBuilder sink;
      if (const gtn::Status st = (*reader)->decodeLevel(level, sink); !st.isOk()) {
        std::fprintf(stderr, "bench-decode: %s\n", st.message().c_str());
        return 1;
      }
      ms.push_back(1e3 * (gtn::bench::threadSeconds() - t0));
      tets = sink.mesh().numTets();
    }
    std::sort(ms.begin(), ms.end());
    const double median = ms[ms.size() / 2];
    std::printf("%-40s %9zu tets  min %8.2f ms  median %8.2f ms  %6.1f ns/tet\n", path.c_str(), tets, ms.front(),
                median, tets ? 1e6 * median / static_cast<double>(tets) : 0.0);
  }
  return 0;
}
