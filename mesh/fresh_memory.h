// Large buffers: a decoder's output, the ranking's star lists and per-tetrahedron flags, the face
// adjacency. Their pages are mapped in one system call, as huge pages where the system allows them.
//
// Memory new to the process is mapped a page at a time, on the first write to each 4 KiB page: a
// trap that costs about 15 us in the virtual machines this project runs on (a 6 MB buffer takes
// 23 ms to fill that way), more than decoding the values that fill it. madvise(MADV_POPULATE_WRITE)
// maps a whole range at once, about a tenth of that. Where the system lacks it (Linux before 5.14,
// other systems) nothing is done and the pages are mapped on first write as usual. The whole 2 MiB
// pages of the range are asked for as transparent huge pages first (MADV_HUGEPAGE; the default
// "madvise" setting of Linux gives them only where asked): one mapping instead of 512, and one TLB
// entry, which the ranking's and the decoders' reads out of order feel most. Where huge pages are
// off or none is free, the small pages are mapped as before.
#pragma once

#include <cstddef>
#include <vector>

namespace gtn {

// Buffers smaller than this are left alone (the allocator usually hands out pages already mapped).
inline constexpr size_t kPopulateMinBytes = size_t{1} << 16;

// Maps the pages of [p, p + bytes) for writing now, where the system can; a hint, never an error.
void populateForWrite(const void* p, size_t bytes);

// v.reserve(n), with the new storage's pages mapped in one call (populateForWrite). For a vector or
// a string.
template <class Contiguous>
void reservePopulated(Contiguous& v, size_t n) {
  if (n <= v.capacity()) return;
  v.reserve(n);
  const size_t bytes = n * sizeof(typename Contiguous::value_type);
  if (bytes >= kPopulateMinBytes) populateForWrite(v.data(), bytes);
}

// v.resize(n) (new elements value-initialized), its storage's pages mapped first.
template <class T>
void resizePopulated(std::vector<T>& v, size_t n) {
  reservePopulated(v, n);
  v.resize(n);
}

// v.assign(n, value) into storage whose new pages are mapped first.
template <class T>
void assignPopulated(std::vector<T>& v, size_t n, const T& value) {
  if (n > v.capacity()) {
    v.clear();
    reservePopulated(v, n);
  }
  v.assign(n, value);
}

// For a vector that grows by appends into storage reserved ahead (perhaps from a count a file
// declares, so not all of it may be used): keeps the pages up to a step (1 MiB) past its end mapped,
// so that appends do not fault a page at a time, and never maps more than a step beyond what is used.
class PopulatedPrefix {
 public:
  // Before appending `adding` elements to v.
  template <class T>
  void before(const std::vector<T>& v, size_t adding) {
    if (v.data() == data_ && v.size() + adding <= ready_) [[likely]]
      return;
    extend(v.data(), v.size(), v.size() + adding, v.capacity(), sizeof(T));
  }

 private:
  void extend(const void* data, size_t size, size_t need, size_t capacity, size_t item);
  const void* data_ = nullptr;
  size_t ready_ = 0;  // elements of data_ whose pages are mapped
};

}  // namespace gtn
