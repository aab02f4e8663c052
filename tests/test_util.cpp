#include "test_util.h"

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

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

std::string tempDir(const std::string& name) {
  std::filesystem::path p = std::filesystem::temp_directory_path() /
                            ("gtn-test-" + std::to_string(getpid()) + "-" + name);
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
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
  const std::string full = std::string(kSanitizerEnv) + "(" + command + ") >" + base + ".out 2>" + base + ".err </dev/null";
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
  static const std::string cache = std::filesystem::temp_directory_path() / ("gtn-test-cache-" + std::to_string(getpid()));
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

}  // namespace gtn::test
