// Shared helpers for the test suites: where the datasets are, running the gtn binary, temp dirs.
#pragma once

#include <string>

namespace gtn::test {

// GTN_DATA_DIR, or ../shared/data relative to the project root.
std::string dataDir();
std::string dataPath(const std::string& relative);
// A fresh empty directory under the build's temp area, removed by nothing (ctest cleans the tree).
std::string tempDir(const std::string& name);

struct RunResult {
  int exit_code = -1;
  std::string out, err;
};
// Runs the gtn binary with the given argument string (shell-quoted by the caller).
RunResult runGtn(const std::string& args);
// Runs an arbitrary shell command, capturing stdout and stderr.
RunResult runShell(const std::string& command);
std::string readFile(const std::string& path);
void writeFile(const std::string& path, const std::string& data);
bool fileExists(const std::string& path);

}  // namespace gtn::test
