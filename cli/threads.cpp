#include "cli/threads.h"

#include <cerrno>
#include <cstdlib>
#include <string>

namespace gtn::cli {

namespace {
// More threads than this is a typing error rather than a machine (TBB would clamp it silently).
constexpr long kMaxThreads = 4096;
}  // namespace

void ThreadLimit::addOption(CLI::App* command) {
  command->add_option("--threads", threads_, "Threads to use, 1 or more (default: every core)")
      ->type_name("N")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            char* end = nullptr;
            errno = 0;
            const long n = std::strtol(text.c_str(), &end, 10);
            if (end == text.c_str() || *end != '\0' || errno != 0 || n < 1 || n > kMaxThreads)
              return "'" + text + "' is not a number of threads: expected a whole number from 1 to " +
                     std::to_string(kMaxThreads);
            return "";
          },
          "N >= 1"));
}

void ThreadLimit::apply() {
  if (threads_ > 0)
    control_ = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                     static_cast<size_t>(threads_));
}

int ThreadLimit::active() {
  return static_cast<int>(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

}  // namespace gtn::cli
