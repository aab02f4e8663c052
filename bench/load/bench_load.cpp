// bench-load: the time to load level 0 of a mesh into memory (points, tetrahedra, every point and
// cell field), Gatun's in-process decode of a level-0 .gtn file against VTK's in-process read of the
// same mesh as .vtu files VTK wrote (zlib, lz4, uncompressed), on blunt fin 5-split, combustion
// 5-split and bunny of ../shared/data (or GTN_DATA_DIR).
//
//   build/bench-load [DATA_DIR] [--reps N] [--datasets NAME,...] [--gtn PATH] [--python PATH] [--keep]
//
// For each dataset: `gtn convert --levels 0 --no-merge-tree` writes the .gtn file, `gtn export`
// writes its level 0 as .vtu, and bench/vtk_vtu.py has VTK (vtkXMLUnstructuredGridWriter, appended
// binary, VTK's default settings otherwise) write that mesh again as zlib, lz4 and raw (uncompressed)
// .vtu files. Then, after one warm-up load of each file, N rounds (default 7), each loading every
// file once in turn (interleaved, so that a change in the machine's load falls on all of them alike):
//   gtn  what `gtn export` does to read a level, in this process: GtnReader opened as `gtn export`
//        opens it (openGtnChecked, random access through the directory, every chunk checksummed),
//        level 0 decoded into a TetMesh (TetMeshBuilder), every field;
//   vtu  a new vtkXMLUnstructuredGridReader's Update() alone, every point and cell array, timed in a
//        warm Python process (bench/vtk_vtu.py serve) that this program starts once.
// Files are read from the page cache after the warm-up, for both. Times are wall-clock: the median of
// the N rounds and the range [min-max], in milliseconds; below each row, the medians of process CPU
// time (this process for gtn, the Python process for VTK) and their ratios, which other processes on
// a shared machine disturb less than the wall-clock figures. Sizes in bytes: the level-0 .gtn file and
// the zlib .vtu. The targets: gtn/zlib (median against median) at most 1 (load not slower than the
// zlib .vtu) and zlib/gtn bytes at least 3.5 (level 0 at least 3.5 times smaller); gtn/lz4 is shown
// as a stretch figure, not judged.
//
// Exit status: 1 when a dataset fails (convert, export, VTK's writer or reader, decode, or the two
// loads disagree on the counts; the other datasets are still measured); else 2 on a usage error
// (nothing measured); else 3 when a target is missed; else 0.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "format/gtn_reader.h"
#include "mesh/mesh_stream.h"

namespace {

using gtn::bench::Dataset;

constexpr double kMaxGtnOverZlib = 1.0;       // load time, gtn / zlib .vtu
constexpr double kMinZlibOverGtnBytes = 3.5;  // zlib .vtu bytes / level-0 .gtn bytes
constexpr const char* kVtuKinds[3] = {"zlib", "lz4", "raw"};

double processCpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// VTK's reader in a Python process of its own (bench/vtk_vtu.py serve), asked one file per line.
class VtkReaderProcess {
 public:
  ~VtkReaderProcess() { stop(); }

  bool start(const std::string& python, const std::string& script) {
    int to_child[2], from_child[2];
    if (pipe(to_child) != 0) return false;
    if (pipe(from_child) != 0) {
      close(to_child[0]);
      close(to_child[1]);
      return false;
    }
    pid_ = fork();
    if (pid_ < 0) return false;
    if (pid_ == 0) {
      dup2(to_child[0], 0);
      dup2(from_child[1], 1);
      close(to_child[0]);
      close(to_child[1]);
      close(from_child[0]);
      close(from_child[1]);
      execl(python.c_str(), python.c_str(), script.c_str(), "serve", static_cast<char*>(nullptr));
      std::fprintf(stderr, "bench-load: cannot run %s: %s\n", python.c_str(), std::strerror(errno));
      _exit(127);
    }
    close(to_child[0]);
    close(from_child[1]);
    to_ = fdopen(to_child[1], "w");
    from_ = fdopen(from_child[0], "r");
    return to_ && from_;
  }

  // Loads `path`; false with `why` set when VTK could not.
  bool load(const std::string& path, double& wall, double& cpu, uint64_t& points, uint64_t& cells, std::string& why) {
    if (!to_ || !from_) {
      why = "VTK's reader process is not running";
      return false;
    }
    std::fprintf(to_, "%s\n", path.c_str());
    std::fflush(to_);
    char* line = nullptr;
    size_t cap = 0;
    const ssize_t n = getline(&line, &cap, from_);
    const std::string answer = n > 0 ? std::string(line, static_cast<size_t>(n)) : std::string();
    std::free(line);
    std::istringstream in(answer);
    unsigned arrays = 0;
    if (in >> wall >> cpu >> points >> cells >> arrays) return true;
    why = answer.empty() ? "VTK's reader process ended (does this Python import VTK?)" : answer;
    while (!why.empty() && why.back() == '\n') why.pop_back();
    return false;
  }

  void stop() {
    if (to_) std::fclose(to_);
    if (from_) std::fclose(from_);
    to_ = from_ = nullptr;
    if (pid_ > 0) waitpid(pid_, nullptr, 0);
    pid_ = -1;
  }

 private:
  pid_t pid_ = -1;
  FILE* to_ = nullptr;
  FILE* from_ = nullptr;
};

// One load of level 0 of `path` as `gtn export` reads it; "" on success, else the error.
std::string gtnLoad(const std::string& path, double& wall, double& cpu, uint64_t& points, uint64_t& tets) {
  const auto w0 = std::chrono::steady_clock::now();
  const double c0 = processCpuSeconds();
  gtn::GtnOpenOptions oo;
  oo.verify = false;
  std::string warnings;
  auto reader = gtn::openGtnChecked(path, oo, [&](const std::string& w) { warnings += w + "; "; });
  if (!reader.isOk()) return reader.status().message();
  gtn::TetMeshBuilder builder;
  if (const gtn::Status st = (*reader)->decodeLevel(0, builder); !st.isOk()) return st.message();
  cpu = processCpuSeconds() - c0;
  wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  points = builder.mesh().numPoints();
  tets = builder.mesh().numTets();
  return warnings.empty() ? "" : "damaged chunks: " + warnings;
}

struct Times {
  std::vector<double> wall, cpu;
  double median(const std::vector<double>& v) const {
    std::vector<double> s = v;
    std::sort(s.begin(), s.end());
    const size_t n = s.size();
    return n == 0 ? 0 : n % 2 ? s[n / 2] : 0.5 * (s[n / 2 - 1] + s[n / 2]);
  }
  double wallMedian() const { return median(wall); }
  double cpuMedian() const { return median(cpu); }
  double wallMin() const { return wall.empty() ? 0 : *std::min_element(wall.begin(), wall.end()); }
  double wallMax() const { return wall.empty() ? 0 : *std::max_element(wall.begin(), wall.end()); }
};

std::string msRange(const Times& t) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.1f [%.1f-%.1f]", 1e3 * t.wallMedian(), 1e3 * t.wallMin(), 1e3 * t.wallMax());
  return buf;
}

}  // namespace

int main(int argc, char** argv) {
  const char* usage =
      "usage: %s [DATA_DIR] [--reps N] [--datasets NAME,...] [--gtn PATH] [--python PATH] [--keep]\n"
      "  NAME: bluntfin/5, combustion/5, bunny (the default) or another dataset of bench-compression\n"
      "  --python: a Python that imports VTK's modules (default /usr/bin/python3; pvpython also works)\n";
  std::string data_arg, gtn_path = GTN_CLI_PATH, python = "/usr/bin/python3", script = GTN_BENCH_VTK_SCRIPT;
  std::vector<std::string> names = {"bluntfin/5", "combustion/5", "bunny"};
  int reps = 7;
  bool keep = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::printf(usage, argv[0]);
      return 0;
    } else if (a == "--reps" && i + 1 < argc && std::atoi(argv[i + 1]) > 0) {
      reps = std::atoi(argv[++i]);
    } else if (a == "--datasets" && i + 1 < argc) {
      names.clear();
      std::istringstream list(argv[++i]);
      for (std::string n; std::getline(list, n, ',');)
        if (!n.empty()) names.push_back(n);
    } else if (a == "--gtn" && i + 1 < argc) {
      gtn_path = argv[++i];
    } else if (a == "--python" && i + 1 < argc) {
      python = argv[++i];
    } else if (a == "--keep") {
      keep = true;
    } else if (a[0] == '-' || !data_arg.empty()) {
      std::fprintf(stderr, "bench-load: unknown or incomplete argument '%s'\n", argv[i]);
      std::fprintf(stderr, usage, argv[0]);
      return 2;
    } else {
      data_arg = a;
    }
  }
  const std::vector<Dataset> shared = gtn::bench::sharedDatasets(
      gtn::bench::dataDir(data_arg.empty() ? nullptr : data_arg.c_str(), GTN_DEFAULT_DATA_DIR));
  std::vector<Dataset> sets;
  for (const std::string& n : names) {
    const auto it = std::find_if(shared.begin(), shared.end(), [&](const Dataset& d) { return d.name == n; });
    if (it == shared.end()) {
      std::fprintf(stderr, "bench-load: no dataset named '%s'\n", n.c_str());
      std::fprintf(stderr, usage, argv[0]);
      return 2;
    }
    sets.push_back(*it);
  }

  std::signal(SIGPIPE, SIG_IGN);  // a reader process that ended is reported by load(), not a signal
  VtkReaderProcess vtk;
  if (!vtk.start(python, script)) {
    std::fprintf(stderr, "bench-load: cannot start %s %s serve\n", python.c_str(), script.c_str());
    return 1;
  }
  std::printf(
      "load of level 0 into memory (points, tetrahedra, all fields), in process; wall ms: median [min-max] of "
      "%d interleaved rounds after a warm-up\n",
      reps);
  std::printf("%-13s %8s | %-24s %-24s %-24s %-24s | %6s %6s | %10s %10s %7s | %s\n", "dataset", "tets", "gtn",
              "zlib.vtu", "lz4.vtu", "raw.vtu", "gtn/", "gtn/", "L0.gtn", "zlib.vtu", "zlib/", "targets");
  std::printf("%-13s %8s | %-24s %-24s %-24s %-24s | %6s %6s | %10s %10s %7s | %s\n", "", "", "", "", "", "", "zlib",
              "lz4", "bytes", "bytes", "gtn", "gtn<=zlib, zlib/gtn>=3.5");
  std::fflush(stdout);
  std::vector<std::string> failed, missed;
  for (const Dataset& d : sets) {
    using gtn::bench::runLogged;
    using gtn::bench::shellQuote;
    const std::string dir = gtn::bench::makeTempDir("gtn-bench-load");
    const auto fail = [&](const std::string& why) {
      std::printf("%-13s failed: %s (files in %s)\n", d.name.c_str(), why.c_str(), dir.c_str());
      std::fflush(stdout);
      failed.push_back(d.name + " (" + why + ")");
    };
    if (dir.empty()) {
      fail("cannot make a temporary directory");
      continue;
    }
    const std::string log = dir + "/log", gtn_file = dir + "/level0.gtn", vtu = dir + "/level0.vtu";
    if (!runLogged(shellQuote(gtn_path) + " convert " + gtn::bench::convertInputs(d) +
                       " -q --levels 0 --no-merge-tree -o " + shellQuote(gtn_file),
                   log)) {
      fail("gtn convert; see " + log);
      continue;
    }
    if (!runLogged(shellQuote(gtn_path) + " export " + shellQuote(gtn_file) + " -o " + shellQuote(vtu), log)) {
      fail("gtn export; see " + log);
      continue;
    }
    if (!runLogged(shellQuote(python) + " " + shellQuote(script) + " write " + shellQuote(vtu) + " " +
                       shellQuote(dir + "/vtk"),
                   log)) {
      fail("VTK's .vtu writer; see " + log);
      continue;
    }
    std::filesystem::remove(vtu);
    std::vector<std::string> files = {gtn_file};
    for (const char* k : kVtuKinds) files.push_back(dir + "/vtk." + k + ".vtu");
    std::vector<Times> times(files.size());
    std::string why;
    uint64_t points = 0, tets = 0;
    // Round 0 is the warm-up, not counted.
    for (int round = 0; round <= reps && why.empty(); ++round)
      for (size_t f = 0; f < files.size() && why.empty(); ++f) {
        double wall = 0, cpu = 0;
        uint64_t p = 0, t = 0;
        if (f == 0) {
          why = gtnLoad(files[f], wall, cpu, p, t);
        } else if (!vtk.load(files[f], wall, cpu, p, t, why)) {
          why = files[f] + ": " + why;
        }
        if (!why.empty()) break;
        if (round == 0 && f == 0) points = p, tets = t;
        if (p != points || t != tets) {
          why = files[f] + ": " + std::to_string(p) + " points, " + std::to_string(t) + " cells, against " +
                std::to_string(points) + " and " + std::to_string(tets) + " decoded from the .gtn file";
          break;
        }
        if (round > 0) times[f].wall.push_back(wall), times[f].cpu.push_back(cpu);
      }
    if (!why.empty()) {
      fail(why);
      continue;
    }
    std::error_code ec;
    const uint64_t gtn_bytes = std::filesystem::file_size(files[0], ec),
                   zlib_bytes = std::filesystem::file_size(files[1], ec);
    const double over_zlib = times[0].wallMedian() / times[1].wallMedian();
    const double over_lz4 = times[0].wallMedian() / times[2].wallMedian();
    const double smaller = static_cast<double>(zlib_bytes) / static_cast<double>(gtn_bytes);
    const bool time_ok = over_zlib <= kMaxGtnOverZlib, size_ok = smaller >= kMinZlibOverGtnBytes;
    std::printf("%-13s %8llu | %-24s %-24s %-24s %-24s | %6.2f %6.2f | %10llu %10llu %7.2f | %s %s\n", d.name.c_str(),
                static_cast<unsigned long long>(tets), msRange(times[0]).c_str(), msRange(times[1]).c_str(),
                msRange(times[2]).c_str(), msRange(times[3]).c_str(), over_zlib, over_lz4,
                static_cast<unsigned long long>(gtn_bytes), static_cast<unsigned long long>(zlib_bytes), smaller,
                time_ok ? "ok" : "MISS", size_ok ? "ok" : "MISS");
    std::printf(
        "%-13s %8s   CPU ms, medians: gtn %.1f, zlib.vtu %.1f, lz4.vtu %.1f, raw.vtu %.1f; gtn/zlib %.2f, "
        "gtn/lz4 %.2f\n",
        "", "", 1e3 * times[0].cpuMedian(), 1e3 * times[1].cpuMedian(), 1e3 * times[2].cpuMedian(),
        1e3 * times[3].cpuMedian(), times[0].cpuMedian() / times[1].cpuMedian(),
        times[0].cpuMedian() / times[2].cpuMedian());
    std::fflush(stdout);
    std::string misses;
    char buf[120];
    if (!time_ok) {
      std::snprintf(buf, sizeof buf, "load %.2f x the zlib .vtu's > %.1f", over_zlib, kMaxGtnOverZlib);
      misses = buf;
    }
    if (!size_ok) {
      std::snprintf(buf, sizeof buf, "zlib .vtu only %.2f x level 0 < %.1f", smaller, kMinZlibOverGtnBytes);
      misses += (misses.empty() ? "" : "; ") + std::string(buf);
    }
    if (!misses.empty()) missed.push_back(d.name + " (" + misses + ")");
    if (keep) std::printf("  files kept in %s\n", dir.c_str());
    else std::filesystem::remove_all(dir);
  }
  vtk.stop();
  std::printf(
      "\ntargets: gtn load <= %.1f x the zlib .vtu's, level 0 .gtn >= %.1f x smaller than the zlib .vtu; %zu "
      "missed%s\n",
      kMaxGtnOverZlib, kMinZlibOverGtnBytes, missed.size(), missed.empty() ? "" : ":");
  for (const std::string& m : missed) std::printf("  %s\n", m.c_str());
  if (!failed.empty()) {
    std::printf("%zu failed:\n", failed.size());
    for (const std::string& f : failed) std::printf("  %s\n", f.c_str());
  }
  return !failed.empty() ? 1 : !missed.empty() ? 3 : 0;
}
