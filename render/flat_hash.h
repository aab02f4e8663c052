// An open-addressing hash map for the streaming renderer's per-front maps (live vertices, open faces):
// one array of entries, linear probing, deletion by backward shift (no tombstones), so a lookup
// touches one or two cache lines and nothing is allocated per entry. A byte per slot beside the
// entries says whether it is used and holds 7 more bits of the key's hash, so a probe compares keys
// only where those bits agree: a miss reads the byte array alone, and the table can be three quarters
// full (half the memory of a half-full one) without slowing lookups down. Sizes follow the live set:
// the table grows by a quarter when it would be over three quarters full and halves when it falls
// under a sixteenth (the renderer's face map swings between a quarter and three quarters full from one
// batch to the next: a table that halved at an eighth was reallocated back and forth). Capacities are
// not powers of two (a position is the high half of the mixed hash times the capacity): doubling
// left a table between 3/8 and 3/4 full at its peak, and combustion's face map at 0.41 full, 1.3 MB.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace gtn {

// Key: equality-comparable and copyable; Hash: size_t operator()(const Key&), whose bits, mixed,
// pick the home slot, and whose bits 24 to 30 are the tag. Pointers returned by find and tryEmplace
// stay valid until the next tryEmplace or erase.
template <class Key, class Value, class Hash>
class FlatHashMap {
 public:
  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }

  Value* find(const Key& k) {
    if (size_ == 0) return nullptr;
    const size_t h = hash_(k);
    const uint8_t tag = tagOf(h);
    for (size_t i = home(h);; i = next(i)) {
      const uint8_t c = ctrl_[i];
      if (c == kEmpty) return nullptr;
      if (c == tag && slots_[i].key == k) return &slots_[i].value;
    }
  }
  const Value* find(const Key& k) const { return const_cast<FlatHashMap*>(this)->find(k); }

  // The value of k, inserted value-initialised if absent; second: whether it was inserted.
  std::pair<Value*, bool> tryEmplace(const Key& k) {
    if (4 * (size_ + 1) > 3 * ctrl_.size()) rehash(ctrl_.empty() ? 16 : ctrl_.size() + ctrl_.size() / 4);
    const size_t h = hash_(k);
    const uint8_t tag = tagOf(h);
    size_t i = home(h);
    for (; ctrl_[i] != kEmpty; i = next(i))
      if (ctrl_[i] == tag && slots_[i].key == k) return {&slots_[i].value, false};
    ctrl_[i] = tag;
    slots_[i].key = k;
    slots_[i].value = Value();
    ++size_;
    return {&slots_[i].value, true};
  }

  // Removes k if present; returns whether it was.
  bool erase(const Key& k) {
    if (size_ == 0) return false;
    const size_t h = hash_(k);
    const uint8_t tag = tagOf(h);
    size_t i = home(h);
    for (;; i = next(i)) {
      if (ctrl_[i] == kEmpty) return false;
      if (ctrl_[i] == tag && slots_[i].key == k) break;
    }
    // Backward shift: move later entries of the probe run into the hole when their home position
    // does not lie cyclically in (hole, their position].
    for (size_t j = next(i); ctrl_[j] != kEmpty; j = next(j)) {
      if (distance(home(hash_(slots_[j].key)), j) >= distance(i, j)) {
        slots_[i] = std::move(slots_[j]);
        ctrl_[i] = ctrl_[j];
        i = j;
      }
    }
    ctrl_[i] = kEmpty;
    --size_;
    if (ctrl_.size() > 64 && 16 * size_ < ctrl_.size()) rehash(ctrl_.size() / 2);
    return true;
  }

  void clear() {
    slots_ = std::vector<Slot>();
    ctrl_ = std::vector<uint8_t>();
    size_ = 0;
  }

  // Calls f(key, value) for every entry.
  template <class F>
  void forEach(F&& f) {
    for (size_t i = 0; i < ctrl_.size(); ++i)
      if (ctrl_[i] != kEmpty) f(slots_[i].key, slots_[i].value);
  }

 private:
  struct Slot {
    Key key;
    Value value;
  };
  static constexpr uint8_t kEmpty = 0;
  static uint8_t tagOf(size_t h) { return static_cast<uint8_t>(0x80 | ((h >> 24) & 0x7F)); }
  size_t home(size_t h) const {
    const uint64_t mixed = static_cast<uint64_t>(h) * 0x9E3779B97F4A7C15ull;
    return static_cast<size_t>((static_cast<unsigned __int128>(mixed) * ctrl_.size()) >> 64);
  }
  size_t next(size_t i) const { return i + 1 == ctrl_.size() ? 0 : i + 1; }
  // Steps from position a forward to position b, wrapping around.
  size_t distance(size_t a, size_t b) const { return b >= a ? b - a : b + ctrl_.size() - a; }

  // The live entries are moved out and the old table freed before the new one is allocated, so that
  // the two tables are never held at once: halving then briefly holds the old table and a sixteenth
  // of it, not one and a half tables; doubling holds three quarters of one table and the new one.
  void rehash(size_t capacity) {
    std::vector<Slot> live;
    live.reserve(size_);
    for (size_t i = 0; i < ctrl_.size(); ++i)
      if (ctrl_[i] != kEmpty) live.push_back(std::move(slots_[i]));
    slots_ = std::vector<Slot>();
    ctrl_ = std::vector<uint8_t>();
    slots_.resize(capacity);
    ctrl_.assign(capacity, kEmpty);
    for (Slot& e : live) {
      const size_t h = hash_(e.key);
      size_t j = home(h);
      while (ctrl_[j] != kEmpty) j = next(j);
      ctrl_[j] = tagOf(h);
      slots_[j] = std::move(e);
    }
  }

  std::vector<Slot> slots_;
  std::vector<uint8_t> ctrl_;
  size_t size_ = 0;
  Hash hash_;
};

}  // namespace gtn
