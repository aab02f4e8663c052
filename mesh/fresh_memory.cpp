#include "mesh/fresh_memory.h"

#include <algorithm>
#include <cstdint>

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace gtn {

void populateForWrite(const void* p, size_t bytes) {
#if defined(__linux__) && defined(MADV_POPULATE_WRITE)
  static const uintptr_t page = [] {
    const long s = sysconf(_SC_PAGESIZE);
    return static_cast<uintptr_t>(s > 0 ? s : 4096);
  }();
  // The whole pages inside the range: a page it shares with other data is left to be mapped as usual.
  const uintptr_t begin = (reinterpret_cast<uintptr_t>(p) + page - 1) & ~(page - 1);
  const uintptr_t end = (reinterpret_cast<uintptr_t>(p) + bytes) & ~(page - 1);
  if (end <= begin) return;
#if defined(MADV_HUGEPAGE)
  // The whole 2 MiB pages inside the range as huge pages, where the system allows them (one trap and
  // one TLB entry for 512 small pages).
  constexpr uintptr_t kHuge = uintptr_t{1} << 21;
  const uintptr_t huge_begin = (begin + kHuge - 1) & ~(kHuge - 1), huge_end = end & ~(kHuge - 1);
  if (huge_end > huge_begin) (void)madvise(reinterpret_cast<void*>(huge_begin), huge_end - huge_begin, MADV_HUGEPAGE);
#endif
  (void)madvise(reinterpret_cast<void*>(begin), end - begin, MADV_POPULATE_WRITE);
#else
  (void)p;
  (void)bytes;
#endif
}

void PopulatedPrefix::extend(const void* data, size_t size, size_t need, size_t capacity, size_t item) {
  constexpr size_t kStep = size_t{1} << 20;
  if (data != data_) {  // new storage: its elements so far were written (copied) already
    data_ = data;
    ready_ = size;
  }
  const size_t target = std::min(capacity, std::max(need, ready_ + std::max<size_t>(1, kStep / item)));
  if (target <= ready_) return;  // the append reallocates; the next call sees the new storage
  populateForWrite(static_cast<const uint8_t*>(data) + ready_ * item, (target - ready_) * item);
  ready_ = target;
}

}  // namespace gtn
