// A TBB task group waited for on every way out of a scope (an early return included), so that its
// tasks never outlive the locals they read.
#pragma once

#include <tbb/task_group.h>

namespace gtn {

struct WaitOnExit {
  tbb::task_group& group;
  ~WaitOnExit() { group.wait(); }
};

}  // namespace gtn
