#include "test_util.h"

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace gtn::test {

std::string dataDir() {
  const char* env = std::getenv("GTN_DATA_DIR");
  if (env && *env) return env;
  return GTN_DEFAULT_DATA_DIR;
}

std::string dataPath(const std::string& relative) { return dataDir() + "/" + relative; }

namespace {
// The directories tempDir made in this process, removed when it ends: unless a test failed (they are
// kept for a look) or GTN_KEEP_TEST_FILES is set. Made after gtest's own instance, so destroyed before it.
struct TempDirs {
  std::vector<std::filesystem::path> made;
  ~TempDirs() {
    const char* keep = std::getenv("GTN_KEEP_TEST_FILES");
    if ((keep && *keep) || ::testing::UnitTest::GetInstance()->Failed()) return;
    for (const std::filesystem::path& p : made) {
      std::error_code ec;
      std::filesystem::remove_all(p, ec);
    }
  }
};
TempDirs& tempDirs() {
  static TempDirs dirs;
  return dirs;
}
}  // namespace

std::string tempDir(const std::string& name) {
  (void)::testing::UnitTest::GetInstance();  // constructed before tempDirs(), destroyed after it
  std::filesystem::path p =
      std::filesystem::temp_directory_path() / ("gtn-test-" + std::to_string(getpid()) + "-" + name);
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  tempDirs().made.push_back(p);
  return p.string();
}

#if defined(__SANITIZE_ADDRESS__)
// Sanitizer builds (GTN_SANITIZE=ON): a finding must fail the test, and a finding in a `gtn` run as a
// subprocess must not pass for exit code 1 (invalid data), which many CLI tests expect: findings exit
// with 86, here and (see runShell) in every command a test runs. UBSan stops at its first finding.
extern "C" const char* __asan_default_options() { return "detect_leaks=1:exitcode=86"; }
extern "C" const char* __ubsan_default_options() { return "print_stacktrace=1:halt_on_error=1:exitcode=86"; }
constexpr const char* kSanitizerEnv =
    "export ASAN_OPTIONS=\"${ASAN_OPTIONS:+$ASAN_OPTIONS:}exitcode=86\" "
    "UBSAN_OPTIONS=\"${UBSAN_OPTIONS:+$UBSAN_OPTIONS:}halt_on_error=1:exitcode=86\"; ";
#else
constexpr const char* kSanitizerEnv = "";
#endif

RunResult runShell(const std::string& command) {
  static int counter = 0;
  const std::string base = std::filesystem::temp_directory_path() /
                           ("gtn-run-" + std::to_string(getpid()) + "-" + std::to_string(counter++));
  const std::string full =
      std::string(kSanitizerEnv) + "(" + command + ") >" + base + ".out 2>" + base + ".err </dev/null";
  const int status = std::system(full.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = readFile(base + ".out");
  r.err = readFile(base + ".err");
  std::remove((base + ".out").c_str());
  std::remove((base + ".err").c_str());
  return r;
}

// The binary's caches (gtn render keeps calibrations and colour ranges under XDG_CACHE_HOME) go to a
// directory of this test process, never to the user's ~/.cache.
RunResult runGtn(const std::string& args) {
  static const std::string cache = tempDir("cache");
  return runShell("XDG_CACHE_HOME=" + cache + " " + std::string(GTN_BINARY) + " " + args);
}

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void writeFile(const std::string& path, const std::string& data) {
  std::ofstream out(path, std::ios::binary);
  out << data;
}

bool fileExists(const std::string& path) {
  struct stat sb;
  return ::stat(path.c_str(), &sb) == 0;
}

nlohmann::json compareJson(const std::string& a, const std::string& b) {
  const RunResult r = runGtn("compare " + a + " " + b + " --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return nlohmann::json::parse(r.out, nullptr, false);
}

std::string shearedHexGridVtk(int n, bool mirrored, bool block_field) {
  std::string s = "# vtk DataFile Version 3.0\nsheared hexahedral grid\nASCII\nDATASET UNSTRUCTURED_GRID\n";
  const int np = n + 1;
  s += "POINTS " + std::to_string(np * np * np) + " double\n";
  char buf[128];
  for (int k = 0; k < np; ++k)
    for (int j = 0; j < np; ++j)
      for (int i = 0; i < np; ++i) {
        std::snprintf(buf, sizeof buf, "%g %g %g\n", i + 0.125 * j, j + 0.25 * k, k + 0.0625 * i);
        s += buf;
      }
  auto id = [np](int i, int j, int k) { return i + np * (j + np * k); };
  const int cells = n * n * n;
  s += "CELLS " + std::to_string(cells) + " " + std::to_string(9 * cells) + "\n";
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int lo = mirrored ? k + 1 : k, hi = mirrored ? k : k + 1;
        const int v[8] = {id(i, j, lo), id(i + 1, j, lo), id(i + 1, j + 1, lo), id(i, j + 1, lo),
                          id(i, j, hi), id(i + 1, j, hi), id(i + 1, j + 1, hi), id(i, j + 1, hi)};
        s += "8";
        for (int c : v) {
          s += ' ';
          s += std::to_string(c);
        }
        s += "\n";
      }
  s += "CELL_TYPES " + std::to_string(cells) + "\n";
  for (int c = 0; c < cells; ++c) s += "12\n";
  s += "POINT_DATA " + std::to_string(np * np * np) + "\nSCALARS density double 1\nLOOKUP_TABLE default\n";
  for (int p = 0; p < np * np * np; ++p) {
    std::snprintf(buf, sizeof buf, "%g\n", std::sin(0.37 * p) + 0.01 * p);
    s += buf;
  }
  if (block_field) {
    s += "CELL_DATA " + std::to_string(cells) + "\nSCALARS block int 1\nLOOKUP_TABLE default\n";
    for (int c = 0; c < cells; ++c) s += std::to_string(c % 7) + "\n";
  }
  return s;
}

const Field* findField(const std::vector<Field>& fields, const std::string& name) {
  for (const Field& f : fields)
    if (f.name == name) return &f;
  return nullptr;
}

bool hasWarning(const ImportReport& report, const std::string& part) {
  for (const std::string& w : report.warnings)
    if (w.find(part) != std::string::npos) return true;
  return false;
}

std::string allWarnings(const ImportReport& report) {
  std::string s;
  for (const std::string& w : report.warnings) s += w + "\n";
  return s;
}

}  // namespace gtn::test
