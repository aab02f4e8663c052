// The slot pool of the level codec (spec section 10.8): a vertex is named by a slot while it is
// live, and the pool holds only the front's vertices, so that the decoder's memory follows the front
// and not the mesh. Slot numbers are coded (an escape or a seed names a slot, candidate ties fall
// back to slot order), so the order in which slots are reused is part of the bitstream: a new vertex
// takes the slot freed last, else the next slot past the end. A retired vertex's slot is freed when
// no open face pins it any more (a face pins the vertex d behind it, whose position its predictions
// read).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "codec/range_coder.h"

namespace gtn::level {

enum SlotState : uint8_t { kFree = 0, kLive = 1, kRetired = 2 };

struct SlotPool {
  std::vector<uint8_t> state;
  std::vector<double> pos;  // 3 per slot
  // Per slot, per axis: the vertex's coordinate minus its prediction before any carry (the
  // prediction rule's, or the boundary's or edge's prediction; 0 for seeds), which later vertices
  // may carry over (spec section 10.5).
  std::vector<float> err;
  std::vector<uint8_t> vals;   // slot_bytes per slot: the values of the decoded point fields
  std::vector<uint32_t> open;  // open front faces on the vertex
  std::vector<uint32_t> pins;  // open front faces whose vertex d it is
  std::vector<uint32_t> ids;   // the vertex's id (its emission order)
  std::vector<uint32_t> free;  // freed slots, the last freed last
  size_t slot_bytes = 0;

  size_t size() const { return state.size(); }
  bool isLive(uint32_t s) const { return s < state.size() && state[s] == kLive; }
  const double* position(uint32_t s) const { return &pos[3 * size_t{s}]; }
  double* position(uint32_t s) { return &pos[3 * size_t{s}]; }
  const uint8_t* values(uint32_t s) const { return &vals[s * slot_bytes]; }
  uint8_t* values(uint32_t s) { return &vals[s * slot_bytes]; }

  // Whether the next alloc() appends a slot to arrays that are full; the owner then grows every
  // per-slot array to grownSize() first (reserve). The pool grows by a quarter, not the vectors' own
  // doubling: its arrays are most of the decoder's memory after the front's edges, and doubling left
  // up to half of them unused (blunt fin's 9748 slots had room for 16384).
  bool full() const { return free.empty() && state.size() == state.capacity(); }
  size_t grownSize() const { return state.size() + state.size() / 4 + 64; }
  void reserve(size_t n) {
    state.reserve(n);
    pos.reserve(3 * n);
    err.reserve(3 * n);
    vals.reserve(slot_bytes * n);
    open.reserve(n);
    pins.reserve(n);
    ids.reserve(n);
  }

  // A live slot with no open face and no pin: the one freed last, else a new one past the end.
  uint32_t alloc() {
    uint32_t s;
    if (!free.empty()) {
      s = free.back();
      free.pop_back();
    } else {
      s = static_cast<uint32_t>(state.size());
      state.push_back(kFree);
      pos.resize(pos.size() + 3);
      err.resize(err.size() + 3);
      vals.resize(vals.size() + slot_bytes);
      open.push_back(0);
      pins.push_back(0);
      ids.push_back(0);
    }
    state[s] = kLive;
    open[s] = 0;
    pins[s] = 0;
    return s;
  }
  // The vertex in s is done: its slot is free now, or once its last pin goes.
  void retire(uint32_t s) {
    state[s] = kRetired;
    if (pins[s] == 0) release(s);
  }
  void pin(uint32_t s) { ++pins[s]; }
  void unpin(uint32_t s) {
    if (--pins[s] == 0 && state[s] == kRetired) release(s);
  }

  // How many direct bits code a slot number: enough for every slot so far.
  int slotBits() const { return bitLength(state.size() > 1 ? state.size() - 1 : 0); }

 private:
  void release(uint32_t s) {
    state[s] = kFree;
    free.push_back(s);
  }
};

}  // namespace gtn::level
