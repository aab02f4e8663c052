// Independent jobs of known, unequal costs on the task arena's threads: each thread takes the
// costliest job left (longest processing time first), so that the large jobs start at once and the
// small ones fill in at the end. A static split of the jobs among the threads (what parallel_for's
// ranges amount to for a handful of jobs) can leave one thread with the two largest; this cannot.
// Which thread runs a job never changes what the job computes, so results do not depend on the
// number of threads.
#pragma once

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <vector>

namespace gtn {

// Calls job(i) once for every i in [0, cost.size()), costliest first (equal costs: lower index first).
template <class Job>
void forEachLongestFirst(const std::vector<uint64_t>& cost, Job&& job) {
  const size_t n = cost.size();
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return cost[a] > cost[b]; });
  std::atomic<size_t> next{0};
  const size_t workers = std::min<size_t>(n, static_cast<size_t>(tbb::this_task_arena::max_concurrency()));
  tbb::parallel_for(size_t{0}, workers, [&](size_t) {
    for (size_t k; (k = next.fetch_add(1)) < n;) job(order[k]);
  });
}

}  // namespace gtn
