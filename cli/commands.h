// The `gtn` subcommands: each file registers one subcommand and returns the function that runs it.
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include "convert/import.h"
#include "mesh/status.h"

namespace gtn::cli {

using Runner = std::function<int()>;
struct Command {
  CLI::App* app;
  Runner run;
};

Command addConvertCommand(CLI::App& app);
Command addInfoCommand(CLI::App& app);
Command addExportCommand(CLI::App& app);
Command addValidateCommand(CLI::App& app);
Command addRenderCommand(CLI::App& app);
Command addCompareCommand(CLI::App& app);
Command addDecodeCommand(CLI::App& app);

// An option's number: finite and at least 0 (`positive`: above 0), with a short message otherwise
// (CLI11's NonNegativeNumber prints the largest double as its bound).
inline CLI::Validator finiteAtLeastZero(bool positive = false) {
  return CLI::Validator(
      [positive](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0' || !std::isfinite(v) || v < 0 || (positive && v == 0))
          return "'" + text + "' is not a finite number " + (positive ? "above 0" : "of 0 or more");
        return "";
      },
      positive ? "NUMBER > 0" : "NUMBER >= 0");
}

// A simplification ratio: a finite number from 0 to 1 (CLI11's Range lets NaN through).
inline CLI::Validator ratioFromZeroToOne() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0' || !(v >= 0 && v <= 1))
          return "'" + text + "' is not a number from 0 to 1";
        return "";
      },
      "0..1");
}

// --box XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX of export and decode into *box (parsed by level_view.h's
// parseBox; an empty one is refused here, since it would read as no box).
inline CLI::Option* addBoxOption(CLI::App* sub, std::string* box) {
  return sub
      ->add_option("--box", *box,
                   "Decode only the pieces of the level whose bounding boxes meet this box, given as "
                   "XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX (the view is those pieces' tetrahedra)")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string { return text.empty() ? "an empty box: 6 numbers are needed" : ""; },
          "XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX"));
}

// Prints "gtn: error: <message>" on standard error and returns the exit code for the status.
int reportError(const Status& status);
// Prints a warning line on standard error.
void warn(const std::string& message);
// Prints what an importer changed (flips, drops, welds, warnings) on standard error.
void printImportReport(const std::string& input, const ImportReport& report);
// An importer's warning about `input`, prefixed with the input's name unless it already names it
// first (TetGen's name the .ele or .node file they are about).
void warnAbout(const std::string& input, const std::string& warning);
// Damage warnings (format/gtn_reader.h's openGtnChecked) held until the command knows its outcome:
// the chunk a command fails on is said once, by the error, not also in a warning before it.
class HeldWarnings {
 public:
  std::function<void(const std::string&)> sink() {
    return [this](const std::string& w) { held_.push_back(w); };
  }
  // Prints the held warnings and forgets them, leaving out one about the chunk whose damage `outcome` reports.
  void flush(const Status& outcome = Status::ok());

 private:
  std::vector<std::string> held_;
};
// JSON as text for standard output; strings that are not UTF-8 (names in files written by older
// versions, file names) get U+FFFD where their bytes are invalid instead of aborting the program.
std::string jsonText(const nlohmann::json& j, int indent = 2);
// The command line as the user typed it.
const std::string& commandLine();
void setCommandLine(int argc, char** argv);
// The command line for provenance (.gtn headers): the program and each argument that is one of
// `paths` (or an option's value that is) reduced to its file name, without directories; --threads N
// is left out (a file's bytes do not depend on the thread count).
std::string commandLineWithFileNames(const std::vector<std::string>& paths);

}  // namespace gtn::cli
