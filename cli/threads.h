// --threads N, on every command: the one place that parses it and bounds the threads the library uses.
#pragma once

#include <CLI/CLI.hpp>

#include <memory>

#include <tbb/global_control.h>

namespace gtn::cli {

// The library's parallel work all runs on TBB (the ranking, the writer's checks beside the encoding,
// the renderers); the only other thread is the progress line's, which computes nothing.
class ThreadLimit {
 public:
  // Adds --threads to `command`; 0 (the default) means every core the process may run on.
  void addOption(CLI::App* command);
  // Bounds TBB to the number given, if one was; the bound holds while this object lives.
  void apply();
  // The number of threads TBB may use now (the bound, or every core).
  static int active();

 private:
  int threads_ = 0;
  std::unique_ptr<tbb::global_control> control_;
};

}  // namespace gtn::cli
