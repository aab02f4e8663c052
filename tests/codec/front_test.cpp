// The peeling front (spec section 10.4): opening a tetrahedron's faces, closing a gate face with the
// next tetrahedron, the edge map the candidates are gathered from, the queue order of gate faces,
// and the pins that keep a retired vertex's slot while a face still predicts from it.
#include "codec/front.h"

#include <gtest/gtest.h>

#include <array>

namespace gtn::level {
namespace {

// Opens the four faces of tetrahedron e as the level codec does: face k is e[kTetFace[k]], with e[k]
// behind it. Returns the faces' indices.
std::array<long, 4> openTet(Front& front, SlotPool& pool, const uint32_t e[4], const long closes[4]) {
  std::array<long, 4> idx{-1, -1, -1, -1};
  for (int k = 0; k < 4; ++k) {
    if (closes[k] >= 0) continue;
    const uint32_t f[3] = {e[kTetFace[k][0]], e[kTetFace[k][1]], e[kTetFace[k][2]]};
    idx[k] = front.open(f, e[k], kNoIndex, pool);
  }
  return idx;
}

TEST(Front, OpensAndClosesFacesWithTheirEdgesCountsAndPins) {
  SlotPool pool;
  for (int i = 0; i < 5; ++i) pool.alloc();
  Front front;
  const uint32_t t0[4] = {0, 1, 2, 3};
  const long none[4] = {-1, -1, -1, -1};
  const std::array<long, 4> f0 = openTet(front, pool, t0, none);
  for (uint32_t s = 0; s < 4; ++s) {
    EXPECT_EQ(pool.open[s], 3u) << s;
    EXPECT_EQ(pool.pins[s], 1u) << s;
  }
  // Face 3 is (0, 2, 1): its directed edges map to the third vertex.
  EXPECT_EQ(front.edges.find(0, 2, kNoIndex), 1u);
  EXPECT_EQ(front.edges.find(2, 1, kNoIndex), 0u);
  EXPECT_EQ(front.edges.find(1, 0, kNoIndex), 2u);
  EXPECT_EQ(front.edges.find(0, 1, kNoIndex), 3u);  // face 2, (0, 1, 3)
  const uint32_t any_order[3] = {2, 1, 0};
  EXPECT_EQ(front.find(any_order), f0[3]);
  // Gate faces come in the order they were opened.
  EXPECT_EQ(front.peekGate(), f0[0]);
  EXPECT_EQ(front.nextGate(), f0[0]);
  EXPECT_EQ(front.nextGate(), f0[1]);
  // The tetrahedron (0, 1, 2, 4) behind face 3 of t0 closes it (its own face 3) and opens three.
  const uint32_t t1[4] = {0, 1, 2, 4};
  const long closes[4] = {-1, -1, -1, f0[3]};
  const FrontFace closed = front.close(f0[3], 3, t1, closes, pool);
  EXPECT_EQ(closed.d, 3u);
  EXPECT_EQ(pool.pins[3], 0u);
  EXPECT_EQ(front.find(any_order), -1);
  EXPECT_EQ(front.edges.find(0, 2, kNoIndex), kNoIndex);
  EXPECT_EQ(front.edges.find(1, 0, kNoIndex), kNoIndex);
  openTet(front, pool, t1, closes);
  EXPECT_EQ(front.edges.find(1, 2, kNoIndex), 4u);  // face 0 of t1, (1, 2, 4)
  EXPECT_EQ(front.edges.find(2, 1, kNoIndex), kNoIndex);
  EXPECT_EQ(pool.open[0], 2u + 2u);
  EXPECT_EQ(pool.open[4], 3u);
  EXPECT_EQ(pool.pins[4], 0u);  // t1's face 3, which 4 is behind, is the closed one
  EXPECT_EQ(pool.pins[0], 2u);
  // Entries of faces closed since are skipped: face 2 of t0 is next, then face 3 is gone.
  EXPECT_EQ(front.nextGate(), f0[2]);
  const FrontFace next = front.faces.at(front.nextGate());  // t1's face 0, (1, 2, 4)
  EXPECT_EQ(next.d, 0u);
  EXPECT_EQ(next.v[0], 1u);
  EXPECT_EQ(next.v[2], 4u);
}

TEST(Front, ARetiredVertexKeepsItsSlotWhileAFacePredictsFromIt) {
  SlotPool pool;
  for (int i = 0; i < 4; ++i) pool.alloc();
  Front front;
  const uint32_t f[3] = {0, 2, 1};
  const long idx = front.open(f, 3, kNoIndex, pool);
  pool.retire(3);
  EXPECT_EQ(pool.alloc(), 4u);  // 3 is still pinned
  const uint32_t e[4] = {0, 1, 2, 4};
  const long closes[4] = {-1, -1, -1, idx};
  front.close(idx, 3, e, closes, pool);
  EXPECT_EQ(pool.alloc(), 3u);  // freed with its last pin
  EXPECT_EQ(front.nextGate(), -1);
}

TEST(Front, AQueueEntryTakesAFaceReopenedOnItsVerticesNotTheRecordItHad) {
  SlotPool pool;
  for (int i = 0; i < 8; ++i) pool.alloc();
  Front front;
  const uint32_t f[3] = {0, 2, 1}, other[3] = {5, 6, 7}, again[3] = {1, 0, 2};
  const long a = front.open(f, 3, kNoIndex, pool);
  const uint32_t e[4] = {0, 1, 2, 4};
  const long closes[4] = {-1, -1, -1, a};
  front.close(a, 3, e, closes, pool);
  const long b = front.open(other, kNoIndex, kNoIndex, pool);
  EXPECT_EQ(b, a);                                      // the freed record is taken first
  const long c = front.open(again, 4, kNoIndex, pool);  // the same vertices, reopened
  EXPECT_NE(c, a);
  // The first entry (opened with record a, now another face's) takes the reopened face; so does the
  // third, whose own face it is, once more; the second is b's.
  EXPECT_EQ(front.peekGate(), c);
  EXPECT_EQ(front.nextGate(), c);
  EXPECT_EQ(front.nextGate(), b);
  EXPECT_EQ(front.nextGate(), c);
  EXPECT_EQ(front.nextGate(), -1);
}

}  // namespace
}  // namespace gtn::level
