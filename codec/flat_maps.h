// Containers for the peeling front. Everything is found through the vertex slot it hangs from: a
// slot owns a bucket of its edges, chained to overflow buckets when it holds more, and heads a chain
// of its faces. A walk around a vertex, or the lookup of a face, then touches one or two lines
// instead of missing all over a hash table of the whole front. Sizes follow the front (the slot
// pool), not the mesh.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "mesh/index.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace gtn {

// Bit i set when a[i] == v, for i < kLanes rounded up to a multiple of 4; lanes past the caller's
// count must be masked off by the caller (they may be read from the memory that follows).
template <uint32_t kLanes>
inline uint64_t equalLanes(const uint32_t* a, uint32_t v) {
  static_assert(kLanes <= 64);
  uint64_t m = 0;
#if defined(__SSE2__)
  const __m128i key = _mm_set1_epi32(static_cast<int>(v));
  for (uint32_t g = 0; g < (kLanes + 3) / 4; ++g) {
    const __m128i x = _mm_loadu_si128(reinterpret_cast<const __m128i*>(a + 4 * g));
    m |= static_cast<uint64_t>(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(x, key)))) << (4 * g);
  }
#else
  for (uint32_t i = 0; i < kLanes; ++i) m |= static_cast<uint64_t>(a[i] == v) << i;
#endif
  return m;
}

// An array of T grown a chunk of 2^kShift entries at a time: growing moves nothing (a vector holds
// its old and new buffers at once while it grows, and the edge buckets' growth was then the
// decoder's, and the streaming renderer's, peak of memory), and addresses stay put. Entries past
// the size are default values.
template <class T, uint32_t kShift>
class ChunkedArray {
 public:
  size_t size() const { return size_; }
  T& operator[](size_t i) { return chunks_[i >> kShift][i & kMask]; }
  const T& operator[](size_t i) const { return chunks_[i >> kShift][i & kMask]; }
  // Grows to n entries (n >= size()), the new ones default values.
  void grow(size_t n) {
    while ((chunks_.size() << kShift) < n) chunks_.push_back(std::make_unique<T[]>(kChunk));
    size_ = n;
  }
  void clear() {
    chunks_.clear();
    size_ = 0;
  }

 private:
  static constexpr size_t kChunk = size_t{1} << kShift, kMask = kChunk - 1;
  std::vector<std::unique_ptr<T[]>> chunks_;
  size_t size_ = 0;
};

// The 64-bit key of the directed edge (a, b): a in the high half.
inline uint64_t edgeKey(uint32_t a, uint32_t b) { return (uint64_t{a} << 32) | b; }

// Map from a directed edge (a, b) of slots (never ~0) to a 32-bit value, stored with a. Slot a's
// entries sit in its bucket, one cache line, chained to overflow buckets when it holds more; keys
// and values in separate arrays, so that a lookup compares all of a bucket's keys at once, without
// a data-dependent branch per entry. A bucket's key lanes past its entries hold kNoIndex, which no key
// equals, so that a lookup needs no count. Removing an entry moves the slot's last entry into its
// place.
class EdgeMap {
  static constexpr uint32_t kCap = 7;
  struct alignas(64) Bucket {
    uint32_t key[kCap] = {kNoIndex, kNoIndex, kNoIndex, kNoIndex, kNoIndex, kNoIndex, kNoIndex};
    uint32_t value[kCap] = {};
    uint32_t n = 0;
    uint32_t next = kNoIndex;
  };
  static_assert(sizeof(Bucket) == 64);

 public:
  // Value for (a, b), or `none`.
  uint32_t find(uint32_t a, uint32_t b, uint32_t none) const {
    return a < head_.size() ? findIn(&head_[a], b, none) : none;
  }
  // The same with the edge packed as (a << 32) | b.
  uint32_t find(uint64_t key, uint32_t none) const { return find(hi(key), lo(key), none); }

  // The edges from one slot a, located once for a walk around a: find(b, none) is what
  // EdgeMap::find(a, b, none) gives, while the map does not change.
  class From {
   public:
    uint32_t find(uint32_t b, uint32_t none) const { return head_ ? map_->findIn(head_, b, none) : none; }

   private:
    friend class EdgeMap;
    From(const EdgeMap* map, const Bucket* head) : map_(map), head_(head) {}
    const EdgeMap* map_;
    const Bucket* head_;
  };
  From from(uint32_t a) const { return From(this, a < head_.size() ? &head_[a] : nullptr); }

  // Sets the value of (a, b), replacing an existing one. Always inline, as eraseIf: the front's
  // updates are most of what the codec does per face, and a call costs as much as the usual update.
  [[gnu::always_inline]] void put(uint32_t a, uint32_t b, uint32_t value) {
    if (a >= head_.size()) head_.grow(size_t{a} + 1);
    Bucket* k = &head_[a];
    uint32_t ref = kNoIndex;  // k's index in extra_, kNoIndex for the head bucket
    while (true) {
      if (const uint32_t m = lanes(*k, b)) {
        k->value[__builtin_ctz(m)] = value;
        return;
      }
      if (k->next == kNoIndex) break;
      ref = k->next;
      k = &extra_[ref];
    }
    if (k->n == kCap) k = chainBucket(a, ref);
    k->key[k->n] = b;
    k->value[k->n++] = value;
    ++size_;
  }
  void put(uint64_t key, uint32_t value) { put(hi(key), lo(key), value); }

  // Removes (a, b) if it maps to `value`.
  [[gnu::always_inline]] void eraseIf(uint32_t a, uint32_t b, uint32_t value) {
    if (a >= head_.size()) return;
    Bucket* const head = &head_[a];
    Bucket* k = head;
    uint32_t m;
    while (!(m = lanes(*k, b))) {
      if (k->next == kNoIndex) return;
      k = &extra_[k->next];
    }
    const uint32_t i = __builtin_ctz(m);
    if (k->value[i] != value) return;
    --size_;
    // The slot's last entry fills the hole.
    Bucket* prev = nullptr;
    Bucket* last = head;
    uint32_t last_ref = kNoIndex;
    while (last->next != kNoIndex) {
      prev = last;
      last_ref = last->next;
      last = &extra_[last_ref];
    }
    const uint32_t l = --last->n;
    k->key[i] = last->key[l];
    k->value[i] = last->value[l];
    last->key[l] = kNoIndex;
    if (last->n == 0 && prev) {
      prev->next = kNoIndex;
      free_.push_back(last_ref);
    }
  }
  void eraseIf(uint64_t key, uint32_t value) { eraseIf(hi(key), lo(key), value); }

  // Starts loading slot `a`'s bucket into the cache.
  void prefetch(uint32_t a) const {
    if (a < head_.size()) __builtin_prefetch(&head_[a]);
  }
  void clear() {
    head_.clear();
    extra_.clear();
    free_.clear();
    size_ = 0;
  }
  size_t size() const { return size_; }

 private:
  static uint32_t hi(uint64_t key) { return static_cast<uint32_t>(key >> 32); }
  static uint32_t lo(uint64_t key) { return static_cast<uint32_t>(key); }
  // Bit i set when bucket k's key i is b (equalLanes also compares value[0], as an eighth lane).
  static uint32_t lanes(const Bucket& k, uint32_t b) {
    return static_cast<uint32_t>(equalLanes<kCap>(k.key, b)) & ((1u << kCap) - 1);
  }
  uint32_t findIn(const Bucket* k, uint32_t b, uint32_t none) const {
    while (true) {
      if (const uint32_t m = lanes(*k, b)) return k->value[__builtin_ctz(m)];
      if (k->next == kNoIndex) return none;
      k = &extra_[k->next];
    }
  }
  // A new empty bucket chained after slot a's full last bucket (extra_[ref], or its head bucket for
  // kNoIndex).
  [[gnu::noinline]] Bucket* chainBucket(uint32_t a, uint32_t ref) {
    uint32_t fresh;
    if (!free_.empty()) {
      fresh = free_.back();
      free_.pop_back();
    } else {
      fresh = static_cast<uint32_t>(extra_.size());
      extra_.grow(size_t{fresh} + 1);
    }
    (ref == kNoIndex ? head_[a] : extra_[ref]).next = fresh;
    Bucket* k = &extra_[fresh];
    k->next = kNoIndex;
    return k;
  }

  ChunkedArray<Bucket, 9> head_;   // [slot], 32 KiB a chunk
  ChunkedArray<Bucket, 6> extra_;  // overflow buckets, 4 KiB a chunk
  std::vector<uint32_t> free_;
  size_t size_ = 0;
};

// An open face of the peeling front: (a, b, c) oriented so that the undecoded tetrahedron behind it
// is (a, b, c, x) with positive orientation; d is the fourth vertex of the decoded tetrahedron on the
// near side (kNoSlot for a boundary triangle).
struct FrontFace {
  uint32_t v[3];  // v[0] == kEmptyFace marks a free pool entry
  uint32_t d;
  uint32_t cell;  // record of the near tetrahedron's cell values (level codec), or ~0
  // Set by FaceMap: the larger two slots of the sorted key (the smallest heads the face's chain),
  // and the next face of that chain (of free records, while free).
  uint32_t key12[2];
  uint32_t next;
};

// The open faces, at most one per vertex triple: records in a pool whose indices stay valid until
// the face is erased, found through their smallest slot. Each slot heads a chain of its faces linked
// through the records themselves: a slot is the smallest of one or two open faces on average, so
// per-slot buckets (they took 128 bytes a slot, with overflow buckets besides) were mostly empty and
// made the largest of the decoder's structures; a chain costs 4 bytes a slot and 4 a face, and a
// lookup still reads one line of heads, which stays in cache, then the face's own record. A record
// is 32 bytes: the key's smallest slot is the chain's, and the encoder keeps its own data apart.
class FaceMap {
 public:
  static constexpr uint32_t kEmptyFace = kNoIndex;

  static void sortedKey(const uint32_t v[3], uint32_t k[3]) {
    uint32_t a = v[0], b = v[1], c = v[2];
    if (a > b) std::swap(a, b);
    if (b > c) std::swap(b, c);
    if (a > b) std::swap(a, b);
    k[0] = a;
    k[1] = b;
    k[2] = c;
  }
  // Index of the face with sorted key `k`, or -1.
  long find(const uint32_t k[3]) const {
    if (k[0] >= head_.size()) return -1;
    for (uint32_t i = head_[k[0]]; i != kNoIndex; i = pool_[i].next) {
      const FrontFace& f = pool_[i];
      if (f.key12[0] == k[1] && f.key12[1] == k[2]) return i;
    }
    return -1;
  }
  const FrontFace& at(long i) const { return pool_[static_cast<size_t>(i)]; }
  // Whether record i is the open face with sorted key k, which is then what find(k) returns (at most
  // one open face has a key): one record read, no walk along the chain, where a face inserted
  // earlier lies behind the later ones.
  bool holds(uint32_t i, const uint32_t k[3]) const {
    if (i >= pool_.size()) return false;
    const FrontFace& f = pool_[i];
    return f.v[0] != kEmptyFace && f.key12[0] == k[1] && f.key12[1] == k[2] && smallest(f) == k[0];
  }
  // Starts loading record i.
  void prefetchAt(uint32_t i) const {
    if (i < pool_.size()) __builtin_prefetch(&pool_[i]);
  }
  // Inserts a face whose key is absent; returns its index.
  long insert(const FrontFace& f) {
    uint32_t i;
    if (free_ != kNoIndex) {
      i = free_;
      free_ = pool_[i].next;
      pool_[i] = f;
    } else {
      i = static_cast<uint32_t>(pool_.size());
      // Grown by a quarter, as the slots are: doubling left up to half of the records unused.
      if (pool_.size() == pool_.capacity()) pool_.reserve(pool_.size() + pool_.size() / 4 + 64);
      pool_.push_back(f);
    }
    uint32_t k[3];
    sortedKey(f.v, k);
    FrontFace& g = pool_[i];
    g.key12[0] = k[1];
    g.key12[1] = k[2];
    if (k[0] >= head_.size()) head_.resize(size_t{k[0]} + 1, kNoIndex);
    g.next = head_[k[0]];
    head_[k[0]] = i;
    ++size_;
    return i;
  }
  void eraseAt(long index) {
    const uint32_t i = static_cast<uint32_t>(index);
    FrontFace& f = pool_[i];
    uint32_t* link = &head_[smallest(f)];
    while (*link != i) link = &pool_[*link].next;
    *link = f.next;
    f.v[0] = kEmptyFace;
    f.next = free_;
    free_ = i;
    --size_;
  }
  size_t size() const { return size_; }
  void reserveSlots(size_t n) { head_.reserve(n); }
  // Starts loading the head of find(k)'s chain.
  void prefetch(const uint32_t k[3]) const {
    if (k[0] < head_.size()) __builtin_prefetch(&head_[k[0]]);
  }

 private:
  static uint32_t smallest(const FrontFace& f) { return std::min(f.v[0], std::min(f.v[1], f.v[2])); }

  std::vector<uint32_t> head_;  // [smallest slot] -> first face of its chain, or kNoIndex
  std::vector<FrontFace> pool_;
  uint32_t free_ = kNoIndex;  // the last freed record, whose `next` is the one freed before, and so on
  size_t size_ = 0;
};

// FIFO queue in one growing ring buffer (std::deque allocates a block every few hundred pushes),
// grown by a quarter rather than doubled: the level codec's queue of gate faces is among the
// decoder's largest structures.
template <class T>
class RingQueue {
 public:
  bool empty() const { return size_ == 0; }
  size_t size() const { return size_; }
  const T& front() const { return buf_[head_]; }
  // The k-th entry from the front (k < size()).
  const T& at(size_t k) const {
    size_t i = head_ + k;
    if (i >= buf_.size()) i -= buf_.size();
    return buf_[i];
  }
  void pop_front() {
    if (++head_ == buf_.size()) head_ = 0;
    --size_;
  }
  void push_back(const T& v) {
    if (size_ == buf_.size()) grow();
    size_t i = head_ + size_;
    if (i >= buf_.size()) i -= buf_.size();
    buf_[i] = v;
    ++size_;
  }
  void clear() { head_ = size_ = 0; }

 private:
  void grow() {
    std::vector<T> next(buf_.size() + buf_.size() / 4 + 64);
    for (size_t k = 0; k < size_; ++k) {
      size_t i = head_ + k;
      if (i >= buf_.size()) i -= buf_.size();
      next[k] = buf_[i];
    }
    head_ = 0;
    buf_.swap(next);
  }

  std::vector<T> buf_;
  size_t head_ = 0, size_ = 0;
};

}  // namespace gtn
