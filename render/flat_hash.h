// An open-addressing hash map for the streaming renderer's per-front maps (live vertices, open faces):
// one array of entries, linear probing, deletion by backward shift (no tombstones), so a lookup
// touches one or two cache lines and nothing is allocated per entry. Sizes follow the live set: the
// table doubles when it is over half full and halves when it falls under an eighth.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace gtn {

// Key: equality-comparable and copyable; Hash: size_t operator()(const Key&). Pointers returned by
// find and tryEmplace stay valid until the next tryEmplace or erase.
template <class Key, class Value, class Hash>
class FlatHashMap {
 public:
  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }

  Value* find(const Key& k) {
    if (size_ == 0) return nullptr;
    for (size_t i = hash_(k) & mask_;; i = (i + 1) & mask_) {
      if (!used_[i]) return nullptr;
      if (slots_[i].key == k) return &slots_[i].value;
    }
  }
  const Value* find(const Key& k) const { return const_cast<FlatHashMap*>(this)->find(k); }

  // The value of k, inserted value-initialised if absent; second: whether it was inserted.
  std::pair<Value*, bool> tryEmplace(const Key& k) {
    if (2 * (size_ + 1) > used_.size()) rehash(used_.empty() ? 16 : 2 * used_.size());
    size_t i = hash_(k) & mask_;
    for (; used_[i]; i = (i + 1) & mask_)
      if (slots_[i].key == k) return {&slots_[i].value, false};
    used_[i] = 1;
    slots_[i].key = k;
    slots_[i].value = Value();
    ++size_;
    return {&slots_[i].value, true};
  }

  // Removes k if present; returns whether it was.
  bool erase(const Key& k) {
    if (size_ == 0) return false;
    size_t i = hash_(k) & mask_;
    for (;; i = (i + 1) & mask_) {
      if (!used_[i]) return false;
      if (slots_[i].key == k) break;
    }
    // Backward shift: move later entries of the probe run into the hole when their home position
    // does not lie cyclically in (hole, their position].
    for (size_t j = (i + 1) & mask_; used_[j]; j = (j + 1) & mask_) {
      const size_t home = hash_(slots_[j].key) & mask_;
      if (((j - home) & mask_) >= ((j - i) & mask_)) {
        slots_[i] = std::move(slots_[j]);
        i = j;
      }
    }
    used_[i] = 0;
    --size_;
    if (used_.size() > 64 && 8 * size_ < used_.size()) rehash(used_.size() / 2);
    return true;
  }

  void clear() {
    slots_.clear();
    used_.clear();
    mask_ = 0;
    size_ = 0;
  }

  // Calls f(key, value) for every entry.
  template <class F>
  void forEach(F&& f) {
    for (size_t i = 0; i < used_.size(); ++i)
      if (used_[i]) f(slots_[i].key, slots_[i].value);
  }

 private:
  struct Slot {
    Key key;
    Value value;
  };

  void rehash(size_t capacity) {
    std::vector<Slot> old_slots(capacity);
    std::vector<uint8_t> old_used(capacity, 0);
    old_slots.swap(slots_);
    old_used.swap(used_);
    mask_ = capacity - 1;
    for (size_t i = 0; i < old_used.size(); ++i) {
      if (!old_used[i]) continue;
      size_t j = hash_(old_slots[i].key) & mask_;
      while (used_[j]) j = (j + 1) & mask_;
      used_[j] = 1;
      slots_[j] = std::move(old_slots[i]);
    }
  }

  std::vector<Slot> slots_;
  std::vector<uint8_t> used_;
  size_t mask_ = 0, size_ = 0;
  Hash hash_;
};

}  // namespace gtn
