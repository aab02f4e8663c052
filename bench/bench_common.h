// What the benchmarks share: this thread's CPU time, and the datasets of ../shared/data.
#pragma once

#include <stdlib.h>
#include <time.h>

#include <cstdlib>
#include <string>
#include <vector>

namespace gtn::bench {

// CPU time of this thread, in seconds: what the measured code costs, not what other processes on
// the machine take.
inline double threadSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// `arg` when given, else GTN_DATA_DIR when set, else `fallback` (the build's ../shared/data).
inline std::string dataDir(const char* arg, const char* fallback) {
  if (arg && *arg) return arg;
  const char* env = std::getenv("GTN_DATA_DIR");
  return env && *env ? env : fallback;
}

struct Dataset {
  std::string name;
  std::vector<std::string> inputs;
  int split = 6;
};

// Every dataset of the shared data directory `dir`, the PLOT3D grids with both splits.
inline std::vector<Dataset> sharedDatasets(const std::string& dir) {
  return {
      {"bluntfin/5", {dir + "/plot3d/bluntfinxyz.bin", dir + "/plot3d/bluntfinq.bin"}, 5},
      {"bluntfin/6", {dir + "/plot3d/bluntfinxyz.bin", dir + "/plot3d/bluntfinq.bin"}, 6},
      {"combustion/5", {dir + "/plot3d/combxyz.bin", dir + "/plot3d/combq.bin"}, 5},
      {"combustion/6", {dir + "/plot3d/combxyz.bin", dir + "/plot3d/combq.bin"}, 6},
      {"spx", {dir + "/vtk/spx.vtk"}, 6},
      {"cornell_spheres", {dir + "/tetgen/cornell_spheres.1.ele"}, 6},
      {"cornellbox_orig", {dir + "/tetgen/cornellbox_orig.1.ele"}, 6},
      {"bunny", {dir + "/medit/bunny.mesh"}, 6},
      {"lv_guccione", {dir + "/vtu/lv_guccione.vtu"}, 6},
      {"raptorTetra", {dir + "/vtu/raptorTetra_19409.vtu"}, 6},
      {"Ossicles", {dir + "/vtu/Ossicles.vtu"}, 6},
      {"fire_ug/6", {dir + "/vtu/fire_ug.vtu"}, 6},
  };
}

}  // namespace gtn::bench

// Running the `gtn` program and VTK's Python helper (bench/vtk_vtu.py) from a benchmark.
namespace gtn::bench {

// `s` quoted for /bin/sh.
inline std::string shellQuote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Runs `command` with /bin/sh, its standard output and error appended to `log`; true when it exits 0.
inline bool runLogged(const std::string& command, const std::string& log) {
  const std::string cmd = "(" + command + ") >> " + shellQuote(log) + " 2>&1";
  return std::system(cmd.c_str()) == 0;
}

// A new empty directory under $TMPDIR (or /tmp), or "" when it cannot be made.
inline std::string makeTempDir(const char* stem) {
  const char* tmp = std::getenv("TMPDIR");
  std::string path = std::string(tmp && *tmp ? tmp : "/tmp") + "/" + stem + "-XXXXXX";
  std::vector<char> buf(path.begin(), path.end());
  buf.push_back('\0');
  return mkdtemp(buf.data()) ? std::string(buf.data()) : std::string();
}

// The `gtn convert` arguments that import dataset `d` as the benchmarks import it.
inline std::string convertInputs(const Dataset& d) {
  std::string args;
  for (const std::string& in : d.inputs) args += shellQuote(in) + " ";
  return args + "--split " + std::to_string(d.split);
}

}  // namespace gtn::bench
