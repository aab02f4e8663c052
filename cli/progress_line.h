// The progress line of long commands: the current stage, its percentage when known and the time so
// far, redrawn on standard error about 5 times a second while it is a terminal; nothing otherwise.
#pragma once

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

#include "mesh/progress.h"

namespace gtn::cli {

class ProgressLine {
 public:
  // `command` prefixes the line ("gtn convert"). With `enabled` false (-q), or when standard error is
  // not a terminal, every call does nothing.
  ProgressLine(std::string command, bool enabled);
  ~ProgressLine();  // clears the line
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  bool active() const { return active_; }
  // Sets the stage and its fraction done (negative: unknown); a new stage is drawn at once.
  void update(const std::string& stage, double fraction = -1.0);
  // The callback for library code (mesh/progress.h); valid while this object lives.
  ProgressFn callback();
  // Clears the line and stops redrawing (before the summary is printed).
  void clear();
  // Erases the line of the progress line alive, if any, before another message is printed on standard
  // error (warn and reportError call it); the line comes back at the next redraw.
  static void erase();

 private:
  void draw();  // with mu_ held
  void run();

  std::string command_;
  bool active_ = false;
  std::mutex mu_;
  std::condition_variable wake_;
  bool stop_ = false;
  std::string stage_;
  double fraction_ = -1.0;
  size_t drawn_ = 0;  // characters on the line now
  std::chrono::steady_clock::time_point start_;
  std::thread thread_;
};

}  // namespace gtn::cli
