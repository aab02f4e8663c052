// FlatHashMap against std::unordered_map under random inserts and erases, through growth, shrinking
// and long probe runs (a weak hash puts many keys on one home position).
#include "render/flat_hash.h"

#include <gtest/gtest.h>

#include <random>
#include <unordered_map>

namespace gtn {
namespace {

struct WeakHash {
  size_t operator()(uint32_t k) const { return k % 7; }  // 7 home positions: long runs and wrap-around
};
struct GoodHash {
  size_t operator()(uint32_t k) const { return static_cast<size_t>((k * 0x9E3779B97F4A7C15ull) >> 20); }
};

template <class Hash>
void checkAgainstReference(uint32_t key_range, int ops, uint32_t seed) {
  FlatHashMap<uint32_t, uint64_t, Hash> map;
  std::unordered_map<uint32_t, uint64_t> ref;
  std::mt19937 rng(seed);
  for (int i = 0; i < ops; ++i) {
    const uint32_t k = rng() % key_range;
    // Phases that mostly insert, then mostly erase, so the table grows and shrinks.
    const bool insert = (i / 5000) % 2 == 0 ? rng() % 4 != 0 : rng() % 4 == 0;
    if (insert) {
      const auto [v, inserted] = map.tryEmplace(k);
      ASSERT_EQ(inserted, ref.count(k) == 0) << "key " << k << " at op " << i;
      if (inserted) {
        ASSERT_EQ(*v, 0u);
        *v = uint64_t{k} * 3 + 1;
        ref[k] = *v;
      }
    } else {
      ASSERT_EQ(map.erase(k), ref.erase(k) == 1) << "key " << k << " at op " << i;
    }
    ASSERT_EQ(map.size(), ref.size());
    if (i % 997 == 0) {
      for (uint32_t q = 0; q < key_range; ++q) {
        const uint64_t* v = map.find(q);
        const auto it = ref.find(q);
        ASSERT_EQ(v != nullptr, it != ref.end()) << "key " << q << " at op " << i;
        if (v) {
          ASSERT_EQ(*v, it->second);
        }
      }
    }
  }
  size_t seen = 0;
  map.forEach([&](uint32_t k, uint64_t v) {
    ++seen;
    ASSERT_EQ(ref.at(k), v);
  });
  EXPECT_EQ(seen, ref.size());
}

TEST(FlatHashMap, MatchesUnorderedMapWithAGoodHash) { checkAgainstReference<GoodHash>(4000, 60000, 1); }

TEST(FlatHashMap, MatchesUnorderedMapWhenEveryKeyCollides) { checkAgainstReference<WeakHash>(300, 30000, 2); }

TEST(FlatHashMap, ShrinksWhenEmptied) {
  FlatHashMap<uint32_t, uint32_t, GoodHash> map;
  for (uint32_t k = 0; k < 10000; ++k) *map.tryEmplace(k).first = k;
  for (uint32_t k = 0; k < 10000; ++k) ASSERT_TRUE(map.erase(k));
  EXPECT_TRUE(map.empty());
  EXPECT_EQ(map.find(5), nullptr);
  EXPECT_FALSE(map.erase(5));
  *map.tryEmplace(5).first = 9;
  EXPECT_EQ(*map.find(5), 9u);
}

}  // namespace
}  // namespace gtn
