// Containers for the peeling front. Everything is stored with the vertex slot it hangs from: each
// slot owns one cache-line bucket of entries, chained to overflow buckets when it holds more. A walk
// around a vertex, or the lookup of a face, then touches one or two lines instead of missing all
// over a hash table of the whole front. Sizes follow the front (the slot pool), not the mesh.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace gtn {

// Unordered small lists of `Entry`, one per slot (a non-negative 32-bit index). Removing an entry
// moves the slot's last entry into its place, so entries must not rely on their position.
template <class Entry, uint32_t kInline>
class SlotLists {
 public:
  // First entry of slot `a` for which `match(entry)` holds, or null.
  template <class Match>
  Entry* find(uint32_t a, Match match) {
    if (a >= head_.size()) return nullptr;
    Bucket* k = &head_[a];
    while (true) {
      for (uint32_t i = 0; i < k->n; ++i)
        if (match(k->e[i])) return &k->e[i];
      if (k->next == kNil) return nullptr;
      k = &extra_[k->next];
    }
  }
  template <class Match>
  const Entry* find(uint32_t a, Match match) const {
    return const_cast<SlotLists*>(this)->find(a, match);
  }
  void append(uint32_t a, const Entry& entry) {
    if (a >= head_.size()) head_.resize(size_t{a} + 1);
    uint32_t ref = kNil;  // kNil: the head bucket
    while (bucket(a, ref).next != kNil) ref = bucket(a, ref).next;
    if (bucket(a, ref).n == kInline) {
      uint32_t fresh;
      if (!free_.empty()) {
        fresh = free_.back();
        free_.pop_back();
      } else {
        fresh = static_cast<uint32_t>(extra_.size());
        extra_.emplace_back();
      }
      extra_[fresh].n = 0;
      extra_[fresh].next = kNil;
      bucket(a, ref).next = fresh;
      ref = fresh;
    }
    Bucket& k = bucket(a, ref);
    k.e[k.n++] = entry;
  }
  // Removes `*entry`, which find(a, ...) returned.
  void erase(uint32_t a, Entry* entry) {
    Bucket* prev = nullptr;
    Bucket* last = &head_[a];
    uint32_t last_ref = kNil;
    while (last->next != kNil) {
      prev = last;
      last_ref = last->next;
      last = &extra_[last_ref];
    }
    *entry = last->e[--last->n];
    if (last->n == 0 && prev) {
      prev->next = kNil;
      free_.push_back(last_ref);
    }
  }
  void clear() {
    head_.clear();
    extra_.clear();
    free_.clear();
  }

 private:
  static constexpr uint32_t kNil = 0xFFFFFFFFu;
  struct alignas(64) Bucket {
    uint32_t n = 0;
    uint32_t next = kNil;
    Entry e[kInline];
  };
  Bucket& bucket(uint32_t a, uint32_t ref) { return ref == kNil ? head_[a] : extra_[ref]; }

  std::vector<Bucket> head_;   // [slot]
  std::vector<Bucket> extra_;  // overflow buckets
  std::vector<uint32_t> free_;
};

// Map from a directed edge (a, b) of slots (never ~0) to a 32-bit value, stored with a.
class EdgeMap {
 public:
  // Value for (a, b), or `none`.
  uint32_t find(uint32_t a, uint32_t b, uint32_t none) const {
    const Entry* e = lists_.find(a, [b](const Entry& x) { return x.b == b; });
    return e ? e->value : none;
  }
  // The same with the edge packed as (a << 32) | b.
  uint32_t find(uint64_t key, uint32_t none) const { return find(hi(key), lo(key), none); }
  // Sets the value of (a, b), replacing an existing one.
  void put(uint32_t a, uint32_t b, uint32_t value) {
    if (Entry* e = lists_.find(a, [b](const Entry& x) { return x.b == b; })) {
      e->value = value;
      return;
    }
    lists_.append(a, {b, value});
    ++size_;
  }
  void put(uint64_t key, uint32_t value) { put(hi(key), lo(key), value); }
  // Removes (a, b) if it maps to `value`.
  void eraseIf(uint32_t a, uint32_t b, uint32_t value) {
    Entry* e = lists_.find(a, [b](const Entry& x) { return x.b == b; });
    if (!e || e->value != value) return;
    lists_.erase(a, e);
    --size_;
  }
  void eraseIf(uint64_t key, uint32_t value) { eraseIf(hi(key), lo(key), value); }
  void clear() {
    lists_.clear();
    size_ = 0;
  }
  size_t size() const { return size_; }

 private:
  struct Entry {
    uint32_t b, value;
  };
  static uint32_t hi(uint64_t key) { return static_cast<uint32_t>(key >> 32); }
  static uint32_t lo(uint64_t key) { return static_cast<uint32_t>(key); }

  SlotLists<Entry, 7> lists_;  // 8 + 7 * 8 bytes: one cache line per slot
  size_t size_ = 0;
};

// An open face of the peeling front: (a, b, c) oriented so that the undecoded tetrahedron behind it
// is (a, b, c, x) with positive orientation; d is the fourth vertex of the decoded tetrahedron on the
// near side (kNoSlot for a boundary triangle); tet is the encoder's undecoded tetrahedron.
struct FrontFace {
  uint32_t key[3];  // sorted vertex slots; key[0] == kEmptyFace marks a free pool entry
  uint32_t v[3];
  uint32_t d;
  uint32_t tet;
  uint32_t cell;  // record of the near tetrahedron's cell values (level codec), or ~0
};

// The open faces, at most one per vertex triple: records in a pool whose indices stay valid until
// the face is erased, found through their smallest slot.
class FaceMap {
 public:
  static constexpr uint32_t kEmptyFace = 0xFFFFFFFFu;

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
    const Entry* e = lists_.find(k[0], [k](const Entry& x) { return x.k1 == k[1] && x.k2 == k[2]; });
    return e ? static_cast<long>(e->face) : -1;
  }
  // True if `index` is the face with sorted key `k` (a cheap find() when the index is a guess).
  bool holds(long index, const uint32_t k[3]) const {
    if (index < 0 || static_cast<size_t>(index) >= pool_.size()) return false;
    const FrontFace& f = pool_[static_cast<size_t>(index)];
    return f.key[0] == k[0] && f.key[1] == k[1] && f.key[2] == k[2];
  }
  const FrontFace& at(long i) const { return pool_[static_cast<size_t>(i)]; }
  // Inserts a face whose key is absent; returns its index.
  long insert(const FrontFace& f) {
    uint32_t i;
    if (!free_.empty()) {
      i = free_.back();
      free_.pop_back();
      pool_[i] = f;
    } else {
      i = static_cast<uint32_t>(pool_.size());
      pool_.push_back(f);
    }
    lists_.append(f.key[0], {f.key[1], f.key[2], i});
    ++size_;
    return i;
  }
  void eraseAt(long index) {
    const uint32_t i = static_cast<uint32_t>(index);
    FrontFace& f = pool_[i];
    Entry* e = lists_.find(f.key[0], [i](const Entry& x) { return x.face == i; });
    lists_.erase(f.key[0], e);
    f.key[0] = kEmptyFace;
    free_.push_back(i);
    --size_;
  }
  size_t size() const { return size_; }

 private:
  struct Entry {
    uint32_t k1, k2, face;
  };
  SlotLists<Entry, 4> lists_;  // 8 + 4 * 12 bytes: one cache line per slot
  std::vector<FrontFace> pool_;
  std::vector<uint32_t> free_;
  size_t size_ = 0;
};

// FIFO queue in one growing ring buffer (std::deque allocates a block every few hundred pushes).
template <class T>
class RingQueue {
 public:
  bool empty() const { return head_ == tail_; }
  size_t size() const { return tail_ - head_; }
  const T& front() const { return buf_[head_ & mask_]; }
  void pop_front() { ++head_; }
  void push_back(const T& v) {
    if (tail_ - head_ == buf_.size()) grow();
    buf_[tail_++ & mask_] = v;
  }
  void clear() { head_ = tail_ = 0; }

 private:
  void grow() {
    std::vector<T> next(buf_.empty() ? 64 : 2 * buf_.size());
    for (size_t i = head_; i != tail_; ++i) next[i - head_] = buf_[i & mask_];
    tail_ -= head_;
    head_ = 0;
    buf_.swap(next);
    mask_ = buf_.size() - 1;
  }

  std::vector<T> buf_;
  size_t head_ = 0, tail_ = 0, mask_ = 0;
};

}  // namespace gtn
