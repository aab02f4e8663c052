// Open-addressing hash tables for the peeling front (linear probing, backward-shift deletion, so no
// tombstones accumulate). Their size follows the front, not the mesh.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

namespace gtn {

// Map from a 64-bit key (never ~0) to a 32-bit value.
class EdgeMap {
 public:
  static constexpr uint64_t kEmpty = ~uint64_t{0};
  EdgeMap() { resize(64); }

  // Value for `key`, or `none`.
  uint32_t find(uint64_t key, uint32_t none) const {
    size_t i = slotOf(key);
    while (true) {
      const Entry& e = table_[i];
      if (e.key == key) return e.value;
      if (e.key == kEmpty) return none;
      i = (i + 1) & mask_;
    }
  }
  void put(uint64_t key, uint32_t value) {
    if (2 * (size_ + 1) > table_.size()) resize(2 * table_.size());
    size_t i = slotOf(key);
    while (table_[i].key != kEmpty && table_[i].key != key) i = (i + 1) & mask_;
    if (table_[i].key == kEmpty) ++size_;
    table_[i] = {key, value};
  }
  // Removes `key` if it maps to `value`.
  void eraseIf(uint64_t key, uint32_t value) {
    size_t i = slotOf(key);
    while (true) {
      if (table_[i].key == kEmpty) return;
      if (table_[i].key == key) break;
      i = (i + 1) & mask_;
    }
    if (table_[i].value != value) return;
    eraseAt(i);
  }
  void clear() {
    for (Entry& e : table_) e.key = kEmpty;
    size_ = 0;
  }
  size_t size() const { return size_; }

 private:
  struct Entry {
    uint64_t key;
    uint32_t value;
  };
  // Fibonacci hashing: the top bits of the product depend on every key bit.
  size_t slotOf(uint64_t key) const {
    uint64_t h = key * 0x9E3779B97F4A7C15ull;
    h ^= h >> 31;
    return static_cast<size_t>((h * 0xC2B2AE3D27D4EB4Full) >> shift_);
  }
  void eraseAt(size_t i) {
    size_t j = i;
    while (true) {
      j = (j + 1) & mask_;
      if (table_[j].key == kEmpty) break;
      const size_t home = slotOf(table_[j].key);
      // Move j back into the hole at i unless its home lies cyclically in (i, j].
      const bool in_range = (i <= j) ? (home > i && home <= j) : (home > i || home <= j);
      if (!in_range) {
        table_[i] = table_[j];
        i = j;
      }
    }
    table_[i].key = kEmpty;
    --size_;
  }
  void resize(size_t n) {
    std::vector<Entry> old;
    old.swap(table_);
    table_.assign(n, Entry{kEmpty, 0});
    mask_ = n - 1;
    shift_ = 64 - __builtin_ctzll(n);
    size_ = 0;
    for (const Entry& e : old)
      if (e.key != kEmpty) put(e.key, e.value);
  }

  std::vector<Entry> table_;
  size_t mask_ = 0;
  int shift_ = 64;
  size_t size_ = 0;
};

// An open face of the peeling front: (a, b, c) oriented so that the undecoded tetrahedron behind it
// is (a, b, c, x) with positive orientation; d is the fourth vertex of the decoded tetrahedron on the
// near side (kNoSlot for a boundary triangle); tet is the encoder's undecoded tetrahedron.
struct FrontFace {
  uint32_t key[3];  // sorted vertex slots; key[0] == kEmptyFace marks a free table entry
  uint32_t v[3];
  uint32_t d;
  uint32_t tet;
  uint32_t cell;  // record of the near tetrahedron's cell values (level codec), or ~0
};

class FaceMap {
 public:
  static constexpr uint32_t kEmptyFace = 0xFFFFFFFFu;
  FaceMap() { resize(64); }

  static void sortedKey(const uint32_t v[3], uint32_t k[3]) {
    uint32_t a = v[0], b = v[1], c = v[2];
    if (a > b) std::swap(a, b);
    if (b > c) std::swap(b, c);
    if (a > b) std::swap(a, b);
    k[0] = a;
    k[1] = b;
    k[2] = c;
  }
  // Index of the entry with key `k`, or -1.
  long find(const uint32_t k[3]) const {
    size_t i = slotOf(k);
    while (true) {
      const FrontFace& e = table_[i];
      if (e.key[0] == k[0] && e.key[1] == k[1] && e.key[2] == k[2]) return static_cast<long>(i);
      if (e.key[0] == kEmptyFace) return -1;
      i = (i + 1) & mask_;
    }
  }
  const FrontFace& at(long i) const { return table_[static_cast<size_t>(i)]; }
  // Inserts a face whose key is absent.
  void insert(const FrontFace& f) {
    if (2 * (size_ + 1) > table_.size()) resize(2 * table_.size());
    size_t i = slotOf(f.key);
    while (table_[i].key[0] != kEmptyFace) i = (i + 1) & mask_;
    table_[i] = f;
    ++size_;
  }
  void eraseAt(long index) {
    size_t i = static_cast<size_t>(index);
    size_t j = i;
    while (true) {
      j = (j + 1) & mask_;
      if (table_[j].key[0] == kEmptyFace) break;
      const size_t home = slotOf(table_[j].key);
      const bool in_range = (i <= j) ? (home > i && home <= j) : (home > i || home <= j);
      if (!in_range) {
        table_[i] = table_[j];
        i = j;
      }
    }
    table_[i].key[0] = kEmptyFace;
    --size_;
  }
  size_t size() const { return size_; }

 private:
  size_t slotOf(const uint32_t k[3]) const {
    uint64_t h = (uint64_t{k[0]} * 0x9E3779B97F4A7C15ull) ^ (uint64_t{k[1]} * 0xC2B2AE3D27D4EB4Full) ^
                 (uint64_t{k[2]} * 0x165667B19E3779F9ull);
    h ^= h >> 29;
    return static_cast<size_t>((h * 0x9E3779B97F4A7C15ull) >> shift_);
  }
  void resize(size_t n) {
    std::vector<FrontFace> old;
    old.swap(table_);
    FrontFace empty{};
    empty.key[0] = kEmptyFace;
    table_.assign(n, empty);
    mask_ = n - 1;
    shift_ = 64 - __builtin_ctzll(n);
    size_ = 0;
    for (const FrontFace& e : old)
      if (e.key[0] != kEmptyFace) insert(e);
  }

  std::vector<FrontFace> table_;
  size_t mask_ = 0;
  int shift_ = 64;
  size_t size_ = 0;
};

}  // namespace gtn
