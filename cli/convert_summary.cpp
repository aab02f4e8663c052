#include "cli/convert_summary.h"

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <utility>

#include "convert/export.h"
#include "convert/import.h"
#include "convert/tetgen_layout.h"
#include "format/file_io.h"

namespace gtn::cli {

namespace {

// The size of a file, or -1 when it has none (standard input, a pipe) or cannot be read.
int64_t fileBytes(const std::string& path) {
  struct stat sb;
  if (path == "-" || ::stat(path.c_str(), &sb) != 0 || !S_ISREG(sb.st_mode)) return -1;
  return static_cast<int64_t>(sb.st_size);
}

// The files a TetGen mesh named by `path` (a basename, .node or .ele) takes that exist: .node, .ele
// and .face; other paths as they are.
std::vector<std::string> meshFiles(const std::string& path, bool tetgen) {
  if (!tetgen) return {path};
  const std::string base = tetgen::basePath(path);
  std::vector<std::string> files;
  for (const char* ext : {".node", ".ele", ".face"})
    if (isRegularFile(base + ext)) files.push_back(base + ext);
  return files;
}

// Names and total size of the files (-1: unknown, e.g. standard input or a .p3d meta-file, whose
// data files it names).
std::pair<std::string, int64_t> describeFiles(const std::vector<std::string>& files) {
  std::string names;
  int64_t bytes = files.empty() ? -1 : 0;
  for (const std::string& f : files) {
    names += (names.empty() ? "" : " + ") + f;
    std::string ext = f.size() > 4 ? f.substr(f.size() - 4) : "";
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    const int64_t b = ext == ".p3d" ? -1 : fileBytes(f);
    bytes = bytes < 0 || b < 0 ? -1 : bytes + b;
  }
  return {names, bytes};
}

}  // namespace

void printConvertSummary(const std::vector<std::string>& input_paths, const std::string& output, size_t tets,
                         double seconds) {
  std::vector<std::string> inputs;
  for (const std::string& in : input_paths)
    for (const std::string& f : meshFiles(in, in != "-" && detectInputFormat(in) == InputFormat::kTetgen))
      if (std::find(inputs.begin(), inputs.end(), f) == inputs.end()) inputs.push_back(f);
  const auto [in_names, in_bytes] = describeFiles(inputs);
  const auto [out_names, out_bytes] =
      describeFiles(meshFiles(output, detectOutputFormat(output) == OutputFormat::kTetgen));
  std::string line = "gtn: " + in_names;
  if (in_bytes >= 0) line += " (" + std::to_string(in_bytes) + " bytes)";
  line += " -> " + out_names;
  if (out_bytes >= 0) line += " (" + std::to_string(out_bytes) + " bytes)";
  char buf[160];
  if (in_bytes > 0 && out_bytes >= 0) {
    std::snprintf(buf, sizeof buf, ": %.2f%% of the input",
                  100.0 * static_cast<double>(out_bytes) / static_cast<double>(in_bytes));
    line += buf;
  }
  if (tets > 0 && out_bytes >= 0) {
    std::snprintf(buf, sizeof buf, ", %.2f bits/tet (%zu tetrahedra)",
                  8.0 * static_cast<double>(out_bytes) / static_cast<double>(tets), tets);
    line += buf;
  }
  std::snprintf(buf, sizeof buf, ", %.2f s", seconds);
  line += buf;
  std::fprintf(stderr, "%s\n", line.c_str());
}

}  // namespace gtn::cli
