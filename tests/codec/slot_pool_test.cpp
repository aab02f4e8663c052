// The level codec's slot pool (spec section 10.8): slot reuse order is part of the bitstream, so
// these pin it down: the slot freed last is taken first, a pinned vertex keeps its slot until its
// last pin goes, and a slot number costs enough bits for every slot so far.
#include "codec/slot_pool.h"

#include <gtest/gtest.h>

namespace gtn::level {
namespace {

TEST(SlotPool, TakesTheSlotFreedLastThenGrows) {
  SlotPool pool;
  pool.slot_bytes = 4;
  for (uint32_t s = 0; s < 4; ++s) EXPECT_EQ(pool.alloc(), s);
  EXPECT_EQ(pool.vals.size(), 16u);
  pool.retire(2);
  pool.retire(0);
  EXPECT_FALSE(pool.isLive(0));
  EXPECT_FALSE(pool.isLive(7));
  EXPECT_TRUE(pool.isLive(1));
  EXPECT_EQ(pool.alloc(), 0u);  // freed last
  EXPECT_EQ(pool.alloc(), 2u);
  EXPECT_EQ(pool.alloc(), 4u);  // none free: past the end
  EXPECT_EQ(pool.size(), 5u);
  EXPECT_TRUE(pool.isLive(2));
  EXPECT_EQ(pool.open[2], 0u);
}

TEST(SlotPool, APinnedVertexKeepsItsSlotUntilItsLastPinGoes) {
  SlotPool pool;
  const uint32_t a = pool.alloc(), b = pool.alloc();
  pool.pin(a);
  pool.pin(a);
  pool.retire(a);
  EXPECT_EQ(pool.state[a], kRetired);
  EXPECT_EQ(pool.alloc(), 2u);  // a is not free yet
  pool.unpin(a);
  EXPECT_EQ(pool.alloc(), 3u);
  pool.unpin(a);  // the last pin: now free
  EXPECT_EQ(pool.state[a], kFree);
  EXPECT_EQ(pool.alloc(), a);
  EXPECT_EQ(pool.pins[a], 0u);
  // Unpinning a live vertex frees nothing.
  pool.pin(b);
  pool.unpin(b);
  EXPECT_TRUE(pool.isLive(b));
  EXPECT_EQ(pool.alloc(), 4u);
}

TEST(SlotPool, SlotNumbersCostTheBitsOfTheLargestSlot) {
  SlotPool pool;
  EXPECT_EQ(pool.slotBits(), 0);
  pool.alloc();
  EXPECT_EQ(pool.slotBits(), 0);  // one slot: nothing to say
  pool.alloc();
  EXPECT_EQ(pool.slotBits(), 1);
  for (int i = 0; i < 3; ++i) pool.alloc();
  EXPECT_EQ(pool.slotBits(), 3);  // slots 0..4
  pool.retire(4);
  EXPECT_EQ(pool.slotBits(), 3);  // a freed slot still counts
}

TEST(SlotPool, GrowsByAQuarterWhenFull) {
  SlotPool pool;
  EXPECT_TRUE(pool.full());
  EXPECT_EQ(pool.grownSize(), 64u);
  pool.reserve(pool.grownSize());
  EXPECT_FALSE(pool.full());
  for (int i = 0; i < 64; ++i) pool.alloc();
  EXPECT_TRUE(pool.full());
  EXPECT_EQ(pool.grownSize(), 64u + 16u + 64u);
  pool.retire(5);
  EXPECT_FALSE(pool.full());  // the next slot is a freed one
  double* p = pool.position(3);
  p[0] = 1.5;
  EXPECT_EQ(pool.pos[9], 1.5);
}

}  // namespace
}  // namespace gtn::level
