// gtn: convert, inspect, validate, export, decode and render irregular-grid volume data.
#include <algorithm>
#include <cstdio>
#include <vector>

#if defined(__GLIBC__)
#include <malloc.h>
#endif
#if defined(__linux__)
#include <sys/auxv.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <string>
#endif

#include "cli/commands.h"
#include "cli/progress_line.h"
#include "cli/threads.h"

namespace gtn::cli {

namespace {
std::string g_command_line;
std::vector<std::string> g_arguments;

// A path's last component ("/data/run 3/grid.xyz" gives "grid.xyz"); "-" and names without a
// directory as they are.
std::string fileName(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  if (slash == std::string::npos || slash + 1 == path.size()) return path;
  return path.substr(slash + 1);
}
}  // namespace

int reportError(const Status& status) {
  ProgressLine::erase();
  std::fprintf(stderr, "gtn: error: %s\n", status.message().c_str());
  return exitCodeFor(status.code());
}

std::string jsonText(const nlohmann::json& j, int indent) {
  return j.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

void warn(const std::string& message) {
  ProgressLine::erase();
  std::fprintf(stderr, "gtn: warning: %s\n", message.c_str());
}

void HeldWarnings::flush(const Status& outcome) {
  static const std::string kDamage = "checksum mismatch in chunk '";
  for (const std::string& w : held_) {
    // "<file>: byte offset N: checksum mismatch in chunk 'TAG' (...)": the error on that chunk starts so.
    const size_t at = w.find(kDamage);
    const size_t end = at == std::string::npos ? at : w.find('\'', at + kDamage.size());
    if (!outcome.isOk() && end != std::string::npos && outcome.message().rfind(w.substr(0, end + 1), 0) == 0) continue;
    warn(w);
  }
  held_.clear();
}

void printImportReport(const std::string& input, const ImportReport& r) {
  ProgressLine::erase();
  if (r.flipped)
    std::fprintf(stderr, "gtn: %s: flipped %zu tetrahedra to positive orientation\n", input.c_str(), r.flipped);
  if (r.zero_volume)
    std::fprintf(stderr, "gtn: %s: %zu tetrahedra have zero volume (kept)\n", input.c_str(), r.zero_volume);
  if (r.dropped_cells) std::fprintf(stderr, "gtn: %s: dropped %zu cells\n", input.c_str(), r.dropped_cells);
  if (r.welded_points)
    std::fprintf(stderr, "gtn: %s: welded %zu points, dropped %zu collapsed tetrahedra\n", input.c_str(),
                 r.welded_points, r.collapsed_tets);
  if (r.steiner_points)
    std::fprintf(stderr, "gtn: %s: added %zu Steiner points to split cells conformingly\n", input.c_str(),
                 r.steiner_points);
  for (const std::string& w : r.warnings) warnAbout(input, w);
}

void warnAbout(const std::string& input, const std::string& warning) {
  // A warning that already names the input, or one of its files ("m.1" for "m.1.ele: ..."), as is.
  const bool named =
      warning.rfind(input, 0) == 0 && warning.size() > input.size() &&
      (warning.compare(input.size(), 2, ": ") == 0 ||
       (warning[input.size()] == '.' && warning.find(": ", input.size()) < warning.find(' ', input.size())));
  warn(named ? warning : input + ": " + warning);
}

const std::string& commandLine() { return g_command_line; }

void setCommandLine(int argc, char** argv) {
  g_command_line.clear();
  g_arguments.clear();
  for (int i = 0; i < argc; ++i) {
    if (i) g_command_line += ' ';
    g_command_line += argv[i];
    g_arguments.emplace_back(argv[i]);
  }
}

std::string commandLineWithFileNames(const std::vector<std::string>& paths) {
  auto isPath = [&](const std::string& s) { return std::find(paths.begin(), paths.end(), s) != paths.end(); };
  std::string out;
  for (size_t i = 0; i < g_arguments.size(); ++i) {
    const std::string& arg = g_arguments[i];
    // --threads changes how fast, not what: left out, so that a file is the same whatever it was.
    if (i > 0 && arg.rfind("--threads", 0) == 0) {
      if (arg == "--threads") ++i;  // and its value
      if (arg == "--threads" || arg[9] == '=') continue;
    }
    std::string shown = arg;
    if (i == 0 || isPath(arg)) {
      shown = fileName(arg);
    } else if (arg.size() > 2 && arg[0] == '-') {
      // --output=PATH, or -oPATH (a short option with its value attached).
      const size_t eq = arg.rfind("--", 0) == 0 ? arg.find('=') : std::string::npos;
      if (eq != std::string::npos && isPath(arg.substr(eq + 1)))
        shown = arg.substr(0, eq + 1) + fileName(arg.substr(eq + 1));
      else if (arg[1] != '-' && isPath(arg.substr(2))) shown = arg.substr(0, 2) + fileName(arg.substr(2));
    }
    if (i) out += ' ';
    out += shown;
  }
  return out;
}

}  // namespace gtn::cli

namespace {
// glibc serves a block of 128 KiB or more from its own mapping, but raises that threshold to the
// size of any such block freed (up to 32 MiB): from then on large blocks come from the heap, and a
// freed one stays resident unless it lies at the heap's top. Every command frees large blocks all
// along (rendering: the decoder's per-slot arrays and hash tables as they grow, a level's buffers when
// it ends; converting: each level's encoder, the checks run beside the next level's encoding), so the
// threshold is fixed: every large block is mapped, and unmapped when freed. (On a 2.5 M-tetrahedron
// conversion the peak resident set fell from 268 to 255 MB.)
void returnFreedLargeBlocks() {
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, 128 * 1024);
#endif
}

// glibc's malloc asks for transparent huge pages for the memory it maps (its large blocks and its
// heap) when the tunable glibc.malloc.hugetlb is 1 (glibc 2.35 and later), which a program can only
// set in its environment before it starts: so the command starts itself again, once, with the
// tunable added to GLIBC_TUNABLES, unless it is there already (set by the user, or by this). Every
// large block is mapped anew (returnFreedLargeBlocks), and in 4 KiB pages each page costs a trap on
// its first write (about 15 us in the virtual machines this project runs on): a convert spent about
// a tenth of its time there. Where huge pages are off ("never") or glibc does not know the tunable,
// the second start changes nothing; where the program cannot be started again (no /proc, its file
// gone), it runs as it is.
void askForHugePages(char** argv) {
#if defined(__GLIBC__) && defined(__linux__)
  constexpr const char* kTunable = "glibc.malloc.hugetlb";
  const char* found = std::getenv("GLIBC_TUNABLES");
  if (found && std::strstr(found, kTunable)) return;
  // Started by naming the dynamic loader (ld-linux-x86-64.so.2 gtn ...), the process's file is the
  // loader, which would take the arguments for its own: the kernel then gave the process no
  // interpreter (AT_BASE 0), as it does a static program, and it runs as it is.
  if (getauxval(AT_BASE) == 0) return;
  const bool had = found != nullptr;
  const std::string tunables = had ? found : "";
  const std::string set = (tunables.empty() ? std::string() : tunables + ":") + kTunable + "=1";
  // The program's own file, by its path: a process started from /proc/self/exe would be named "exe"
  // (in ps, top and perf), not after the program.
  char self[4096];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
  if (n <= 0 || static_cast<size_t>(n) >= sizeof self - 1) return;
  self[n] = '\0';
  if (setenv("GLIBC_TUNABLES", set.c_str(), 1) != 0) return;
  execv(self, argv);
  // Not started again (the file is gone, say): go on in this process, and leave the variable as it
  // was for the programs this one starts.
  if (had) setenv("GLIBC_TUNABLES", tunables.c_str(), 1);
  else unsetenv("GLIBC_TUNABLES");
#else
  (void)argv;
#endif
}
}  // namespace

int main(int argc, char** argv) {
  using namespace gtn::cli;
  askForHugePages(argv);
  returnFreedLargeBlocks();
  setCommandLine(argc, argv);
  CLI::App app{"gtn: compressed irregular-grid volume data (tetrahedral meshes) - convert, inspect, export"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("gtn ") + GTN_VERSION_STRING);
  std::vector<Command> commands;
  commands.push_back(addConvertCommand(app));
  commands.push_back(addInfoCommand(app));
  commands.push_back(addExportCommand(app));
  commands.push_back(addValidateCommand(app));
  commands.push_back(addRenderCommand(app));
  commands.push_back(addCompareCommand(app));
  commands.push_back(addDecodeCommand(app));
  std::vector<ThreadLimit> threads(commands.size());  // sized once: each option holds its element's address
  for (size_t i = 0; i < commands.size(); ++i) threads[i].addOption(commands[i].app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? 0 : 2;
  }
  for (size_t i = 0; i < commands.size(); ++i) {
    if (!commands[i].app->parsed()) continue;
    threads[i].apply();
    return commands[i].run();
  }
  return 2;
}
