// The peeling front of the level codec (spec section 10.4): the open faces (each with the vertex d of
// the decoded tetrahedron behind it), their directed edges, and the queue in which faces become gate
// faces. It keeps the slot pool's per-vertex counts of open faces and pins up to date.
#pragma once

#include <cstdint>

#include "codec/flat_maps.h"
#include "codec/slot_pool.h"
#include "mesh/faces.h"
#include "mesh/index.h"

namespace gtn::level {

class Front {
 public:
  FaceMap faces;
  EdgeMap edges;  // directed edge of an open face -> its third vertex

  // Opens the face v (oriented towards the undecoded side) behind which d lies (kNoIndex behind a
  // boundary triangle), with cell-value record `cell`, and queues it. Returns its index in faces.
  uint32_t open(const uint32_t v[3], uint32_t d, uint32_t cell, SlotPool& pool) {
    FrontFace f;
    for (int i = 0; i < 3; ++i) f.v[i] = v[i];
    f.d = d;
    f.cell = cell;
    const uint32_t face = static_cast<uint32_t>(faces.insert(f));
    for (int i = 0; i < 3; ++i) {
      ++pool.open[v[i]];
      edges.put(v[i], v[(i + 1) % 3], v[(i + 2) % 3]);
    }
    if (d != kNoIndex) pool.pin(d);
    QueuedFace q;
    FaceMap::sortedKey(v, q.key);
    q.face = face;
    queue_.push_back(q);
    return face;
  }

  // Closes the open face `index`, face k of the tetrahedron e being emitted, which opens its faces j
  // with closes[j] < 0; returns the face. An edge that such a face puts again, in the same direction,
  // is not erased: the eraseIf would find the new value and do nothing, whether before the put or
  // after. The opened faces run their edges against face k's order in kTetFace (t0, t1, t2): the
  // closed face shares their directions when it is the reverse of that order, and then its edge
  // (t0, t2) is put again by face t1 if opened, and so on.
  FrontFace close(long index, int k, const uint32_t e[4], const long closes[4], SlotPool& pool) {
    const FrontFace f = faces.at(index);
    faces.eraseAt(index);
    for (int i = 0; i < 3; ++i) --pool.open[f.v[i]];
    const int* t = kTetFace[k];
    const uint32_t o0 = e[t[0]], o1 = e[t[1]], o2 = e[t[2]];
    const bool reversed = f.v[0] == o0 ? f.v[1] == o2 : (f.v[1] == o0 ? f.v[2] == o2 : f.v[0] == o2);
    if (reversed) {
      if (closes[t[1]] >= 0) edges.eraseIf(o0, o2, o1);
      if (closes[t[0]] >= 0) edges.eraseIf(o2, o1, o0);
      if (closes[t[2]] >= 0) edges.eraseIf(o1, o0, o2);
    } else {
      edges.eraseIf(o0, o1, o2);
      edges.eraseIf(o1, o2, o0);
      edges.eraseIf(o2, o0, o1);
    }
    if (f.d != kNoIndex) pool.unpin(f.d);
    return f;
  }

  // The open face on vertices v (any order), or -1.
  long find(const uint32_t v[3]) const {
    uint32_t key[3];
    FaceMap::sortedKey(v, key);
    return faces.find(key);
  }

  // The next gate face: the open face of the oldest queue entry that still has one (the face opened
  // with the entry, or one opened later on the same vertices), -1 once the queue is empty.
  long nextGate() {
    while (!queue_.empty()) {
      const QueuedFace q = queue_.front();
      queue_.pop_front();
      const long idx = gateOf(q);
      if (idx >= 0) return idx;
    }
    return -1;
  }
  // The face of the next queue entry if it is still open, else -1 (nothing is popped).
  long peekGate() const { return queue_.empty() ? -1 : gateOf(queue_.front()); }

  // Starts loading the front data of the likely next gate face (and the positions of its vertices
  // in `pool`) while this one is coded: the record of the face opened with the next queue entry,
  // the head of the chain that finds it otherwise, its vertices' edge buckets and positions.
  void prefetchNext(const SlotPool& pool) const {
    if (queue_.empty()) return;
    const QueuedFace& q = queue_.front();
    faces.prefetchAt(q.face);
    faces.prefetch(q.key);
    for (int i = 0; i < 3; ++i) {
      edges.prefetch(q.key[i]);
      if (q.key[i] < pool.size()) __builtin_prefetch(pool.position(q.key[i]));
    }
  }

 private:
  // The sorted key of a face when it was opened: the face is found again by its key (at most one
  // open face has it), which is also how a face opened later on the same vertices is taken at this
  // entry. 16 bytes: the queue keeps the entries of faces closed since (23332 at once on blunt fin).
  struct QueuedFace {
    uint32_t key[3];
    uint32_t face;  // the index of the face opened with the entry: found again without a search
  };
  // The entry's face: the one opened with it if it is still open, else find's answer.
  long gateOf(const QueuedFace& q) const { return faces.holds(q.face, q.key) ? q.face : faces.find(q.key); }

  RingQueue<QueuedFace> queue_;
};

}  // namespace gtn::level
