// libFuzzer target: the importers on arbitrary bytes. The first byte picks the format (the input's
// extension); for TetGen and PLOT3D the rest is cut at its first 0xFF byte into two files (.node and
// .ele, grid and Q file). Whatever the bytes, an import must end in a mesh or a clear error: no crash,
// hang or runaway allocation (run with -rss_limit_mb and -timeout). First bytes 0xF7 and 0xF8 make the
// rest a Medit solution file (.sol, .solb) for a fixed mesh of two tetrahedra; 0xF6 makes it a gmsh
// .msh file. The .p3d meta-file is left out: it names other files, and the fuzzer would be reading
// whatever paths it makes up.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "convert/import.h"

namespace {

const std::string& scratch() {
  static const std::string dir = [] {
    char name[] = "/tmp/gtn-fuzz-import-XXXXXX";
    if (!mkdtemp(name)) std::abort();
    return std::string(name);
  }();
  return dir;
}

void put(const std::string& path, const uint8_t* data, size_t size) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  if (data[0] == 0xF7 || data[0] == 0xF8) {
    static const std::string mesh = [] {
      const std::string path = scratch() + "/fixed.mesh";
      const char text[] =
          "MeshVersionFormatted 2\nDimension 3\nVertices\n5\n0 0 0 1\n1 0 0 1\n0 1 0 1\n0 0 1 1\n"
          "1 1 1 1\nTetrahedra\n2\n1 2 3 4 7\n2 3 4 5 8\nEnd\n";
      put(path, reinterpret_cast<const uint8_t*>(text), sizeof text - 1);
      return path;
    }();
    const std::string sol = scratch() + (data[0] == 0xF7 ? "/in.sol" : "/in.solb");
    put(sol, data + 1, size - 1);
    (void)gtn::importMesh({mesh, sol}, gtn::ImportOptions{});
    return 0;
  }
  static const char* const kExtensions[] = {"vtk", "vtu", "mesh", "meshb", "off", "node", "xyz"};
  const std::string ext = data[0] == 0xF6 ? "msh" : kExtensions[data[0] % (sizeof kExtensions / sizeof kExtensions[0])];
  const uint8_t* body = data + 1;
  const size_t n = size - 1;
  const std::string base = scratch() + "/in";
  std::vector<std::string> inputs;
  if (ext == "node" || ext == "xyz") {
    const void* cut = n > 0 ? std::memchr(body, 0xFF, n) : nullptr;
    const size_t first = cut ? static_cast<size_t>(static_cast<const uint8_t*>(cut) - body) : n;
    const std::string second_ext = ext == "node" ? ".ele" : ".q";
    put(base + "." + ext, body, first);
    if (cut) put(base + second_ext, body + first + 1, n - first - 1);
    if (ext == "node") {
      if (!cut) put(base + ".ele", nullptr, 0);
      inputs = {base};
    } else {
      inputs = {base + ".xyz"};
      if (cut) inputs.push_back(base + ".q");
    }
  } else {
    put(base + "." + ext, body, n);
    inputs = {base + "." + ext};
  }
  (void)gtn::importMesh(inputs, gtn::ImportOptions{});
  return 0;
}
