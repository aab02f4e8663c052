// Shared helpers for the test suites: where the datasets are, running the gtn binary, temp dirs.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "convert/import.h"

namespace gtn::test {

// GTN_DATA_DIR, or ../shared/data relative to the project root.
std::string dataDir();
std::string dataPath(const std::string& relative);
// A fresh empty directory under the system's temporary directory, removed with everything in it when
// the test process ends; kept where a test failed, or where GTN_KEEP_TEST_FILES is set.
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

// `gtn compare A B --json`, parsed (a failed run is a test failure; its JSON is then discarded).
nlohmann::json compareJson(const std::string& a, const std::string& b);

// A sheared n x n x n grid of hexahedra as legacy VTK with the point field "density" (varying);
// `mirrored` lists each hexahedron's top face first, so that every cell is stored with negative
// orientation; `block_field` adds the cell field "block" (the cell's index mod 7).
std::string shearedHexGridVtk(int n, bool mirrored = false, bool block_field = false);

// The field named `name` in `fields`, or null.
const Field* findField(const std::vector<Field>& fields, const std::string& name);
// Whether one of the importer's warnings contains `part`.
bool hasWarning(const ImportReport& report, const std::string& part);
// Every warning of the import, one a line (for failure messages).
std::string allWarnings(const ImportReport& report);

}  // namespace gtn::test
