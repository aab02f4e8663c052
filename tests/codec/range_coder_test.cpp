// The binary range coder of spec section 10.1: round trips, the byte accounting the decoder relies
// on, and the bit model's warm-up (the Krichevsky-Trofimov estimate while both rates are 1/(n + 2)).
#include "codec/range_coder.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace gtn {
namespace {

TEST(BitModel, WarmsUpAsTheKrichevskyTrofimovEstimate) {
  // While n + 2 < 16 both estimates move by 1/(n + 2): p0 after n bits is (zeros + 1/2) / (n + 1),
  // up to the rounding down of each step (at most one unit of 2^-16 per update).
  std::mt19937 rng(3);
  for (int trial = 0; trial < 50; ++trial) {
    BitModel m;
    int zeros = 0;
    for (int n = 1; n <= 14; ++n) {
      const uint32_t bit = rng() % 4 == 0;
      zeros += bit == 0;
      m.update(bit);
      const double kt = 65536.0 * (zeros + 0.5) / (n + 1);
      EXPECT_NEAR(m.p0(), kt, n + 1.0) << "trial " << trial << " after " << n << " bits";
    }
  }
}

TEST(BitModel, SettlesAtTheFinalRates) {
  BitModel m;
  for (int i = 0; i < 1000; ++i) m.update(0);
  EXPECT_EQ(m.seen, kModelWarmup);
  const uint16_t fast = m.fast, slow = m.slow;
  m.update(1);
  // Final rates: 1/16 (4096 / 65536) and 1/128 (512 / 65536), the step rounded down.
  EXPECT_EQ(m.fast, fast - ((fast * 4096u) >> 16));
  EXPECT_EQ(m.slow, slow - ((slow * 512u) >> 16));
}

TEST(BitModel, EstimatesNeverReachZeroOrOne) {
  for (uint32_t bit : {0u, 1u}) {
    BitModel m;
    for (int i = 0; i < 100000; ++i) {
      m.update(bit);
      ASSERT_GE(m.p0(), 1u);
      ASSERT_LE(m.p0(), 65535u);
      ASSERT_GE(m.fast, 1u);
      ASSERT_GE(m.slow, 1u);
    }
  }
}

TEST(RangeCoder, RoundTripsModelledAndDirectBitsAndConsumesExactlyItsBytes) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    // Skewed bits in a few contexts, a long run of one value (extreme probabilities), direct bits.
    std::vector<uint32_t> bits, ctx, direct, widths;
    const int n = 2000 + trial * 500;
    for (int i = 0; i < n; ++i) {
      const uint32_t c = rng() % 4;
      ctx.push_back(c);
      bits.push_back(i > n / 2 && i < n / 2 + 3000 ? 1u : (rng() % (c + 2) == 0));
      const int w = 1 + static_cast<int>(rng() % 32);
      widths.push_back(w);
      direct.push_back(w == 32 ? static_cast<uint32_t>(rng()) : static_cast<uint32_t>(rng()) & ((1u << w) - 1));
    }
    std::vector<uint8_t> out;
    {
      EntropyCoder<true> enc(&out);
      BitModel models[4];
      for (int i = 0; i < n; ++i) {
        enc.bit(models[ctx[i]], bits[i]);
        if (i % 7 == 0) enc.direct(direct[i], widths[i]);
      }
      enc.finish();
    }
    ASSERT_FALSE(out.empty());
    EXPECT_EQ(out[0], 0u);
    EntropyCoder<false> dec(out);
    BitModel models[4];
    for (int i = 0; i < n; ++i) {
      ASSERT_EQ(dec.bit(models[ctx[i]], 0), bits[i]) << "trial " << trial << " bit " << i;
      if (i % 7 == 0) {
        ASSERT_EQ(dec.direct(0, widths[i]), direct[i]) << "trial " << trial << " direct " << i;
      }
    }
    EXPECT_TRUE(dec.finishedCleanly());
    // One byte short: the decoder notices it read past the end.
    std::vector<uint8_t> cut(out.begin(), out.end() - 1);
    EntropyCoder<false> short_dec(cut);
    BitModel m2[4];
    for (int i = 0; i < n; ++i) {
      short_dec.bit(m2[ctx[i]], 0);
      if (i % 7 == 0) short_dec.direct(0, widths[i]);
    }
    EXPECT_FALSE(short_dec.finishedCleanly());
  }
}

TEST(RangeCoder, WarmUpMakesAShortSkewedSequenceCheap) {
  // 64 zeros in one context: the KT estimate codes them in about log2(64) + 1 bits, where a model
  // creeping from 1/2 at fixed rates 1/16 and 1/128 needed 28 bits.
  std::vector<uint8_t> out;
  EntropyCoder<true> enc(&out);
  BitModel m;
  double ideal = 0;
  for (int i = 0; i < 64; ++i) {
    ideal -= std::log2(m.p0() / 65536.0);
    enc.bit(m, 0);
  }
  enc.finish();
  EXPECT_LT(ideal, 8.0);
  EXPECT_LE(out.size(), 1u + 5u + 1u);  // the leading 0, the flush, and at most one byte of payload
}

}  // namespace
}  // namespace gtn
