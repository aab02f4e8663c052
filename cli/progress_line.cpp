#include "cli/progress_line.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>

namespace gtn::cli {

namespace {
std::mutex g_alive_mu;
ProgressLine* g_alive = nullptr;  // the one progress line drawing now
}  // namespace

ProgressLine::ProgressLine(std::string command, bool enabled)
    : command_(std::move(command)),
      active_(enabled && ::isatty(STDERR_FILENO) == 1),
      start_(std::chrono::steady_clock::now()) {
  if (!active_) return;
  {
    std::lock_guard<std::mutex> lock(g_alive_mu);
    g_alive = this;
  }
  thread_ = std::thread([this] { run(); });
}

void ProgressLine::erase() {
  std::lock_guard<std::mutex> alive(g_alive_mu);
  if (!g_alive) return;
  std::lock_guard<std::mutex> lock(g_alive->mu_);
  if (g_alive->drawn_ > 0) std::fprintf(stderr, "\r%*s\r", static_cast<int>(g_alive->drawn_), "");
  std::fflush(stderr);
  g_alive->drawn_ = 0;
}

ProgressLine::~ProgressLine() { clear(); }

void ProgressLine::update(const std::string& stage, double fraction) {
  if (!active_) return;
  std::lock_guard<std::mutex> lock(mu_);
  if (stop_) return;
  const bool changed = stage != stage_;
  stage_ = stage;
  fraction_ = fraction;
  if (changed) draw();
}

ProgressFn ProgressLine::callback() {
  if (!active_) return {};
  return [this](const std::string& stage, double fraction) { update(stage, fraction); };
}

void ProgressLine::clear() {
  if (!active_) return;
  {
    std::lock_guard<std::mutex> alive(g_alive_mu);
    if (g_alive == this) g_alive = nullptr;
  }
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (stop_) return;
    stop_ = true;
    if (drawn_ > 0) std::fprintf(stderr, "\r%*s\r", static_cast<int>(drawn_), "");
    std::fflush(stderr);
    drawn_ = 0;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void ProgressLine::draw() {
  if (stage_.empty()) return;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  char tail[64];
  if (fraction_ >= 0)
    std::snprintf(tail, sizeof tail, " %3d%%  %.1f s", static_cast<int>(std::floor(std::min(fraction_, 1.0) * 100)),
                  seconds);
  else std::snprintf(tail, sizeof tail, "  %.1f s", seconds);
  const std::string line = command_ + ": " + stage_ + tail;
  const size_t pad = drawn_ > line.size() ? drawn_ - line.size() : 0;
  std::fprintf(stderr, "\r%s%*s", line.c_str(), static_cast<int>(pad), "");
  std::fflush(stderr);
  drawn_ = line.size();
}

void ProgressLine::run() {
  std::unique_lock<std::mutex> lock(mu_);
  while (!stop_) {
    wake_.wait_for(lock, std::chrono::milliseconds(200));
    if (!stop_) draw();
  }
}

}  // namespace gtn::cli
