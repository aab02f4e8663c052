// The front containers of the level codec against plain std::map models: the codec's output bytes
// depend on their exact semantics (put replaces, eraseIf removes only on a matching value, at most
// one face per vertex triple, indices stable while a face is open).
#include "codec/flat_maps.h"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <map>
#include <random>
#include <utility>

namespace gtn {
namespace {

TEST(EdgeMap, MatchesAMapUnderRandomOperations) {
  std::mt19937 rng(7);
  EdgeMap edges;
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> model;
  // Few slots and many partners, so that slots overflow their first bucket and chains form.
  std::uniform_int_distribution<uint32_t> slot(0, 40), value(0, 5), op(0, 9);
  for (int step = 0; step < 200000; ++step) {
    const uint32_t a = slot(rng), b = slot(rng), v = value(rng);
    const uint32_t o = op(rng);
    if (o < 5) {
      edges.put(a, b, v);
      model[{a, b}] = v;
    } else if (o < 8) {
      edges.eraseIf(a, b, v);
      auto it = model.find({a, b});
      if (it != model.end() && it->second == v) model.erase(it);
    } else {
      auto it = model.find({a, b});
      ASSERT_EQ(edges.find(a, b, 99u), it == model.end() ? 99u : it->second) << "step " << step;
      ASSERT_EQ(edges.find((uint64_t{a} << 32) | b, 99u), edges.find(a, b, 99u));
      ASSERT_EQ(edges.from(a).find(b, 99u), edges.find(a, b, 99u));
    }
    ASSERT_EQ(edges.size(), model.size());
  }
  for (const auto& [k, v] : model) EXPECT_EQ(edges.find(k.first, k.second, 99u), v);
  edges.clear();
  EXPECT_EQ(edges.size(), 0u);
  EXPECT_EQ(edges.find(3, 4, 99u), 99u);
  EXPECT_EQ(edges.find(1000000, 4, 99u), 99u);  // a slot never seen
  EXPECT_EQ(edges.from(1000000).find(4, 99u), 99u);
}

TEST(FaceMap, FindsEveryOpenFaceByItsSortedKeyAndKeepsIndicesStable) {
  std::mt19937 rng(11);
  FaceMap faces;
  std::map<std::array<uint32_t, 3>, long> model;  // sorted key -> index
  std::uniform_int_distribution<uint32_t> slot(0, 30);
  for (int step = 0; step < 100000; ++step) {
    uint32_t v[3] = {slot(rng), slot(rng), slot(rng)};
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) continue;
    uint32_t k[3];
    FaceMap::sortedKey(v, k);
    ASSERT_TRUE(k[0] < k[1] && k[1] < k[2]);
    const std::array<uint32_t, 3> key = {k[0], k[1], k[2]};
    const long idx = faces.find(k);
    auto it = model.find(key);
    ASSERT_EQ(idx >= 0, it != model.end()) << "step " << step;
    if (idx >= 0) {
      ASSERT_EQ(idx, it->second);  // the index given at insertion still finds the face
      const FrontFace& f = faces.at(idx);
      ASSERT_EQ(f.d, k[0] + k[1] + k[2]);
      faces.eraseAt(idx);
      ASSERT_EQ(faces.find(k), -1);
      model.erase(it);
    } else {
      FrontFace f{};
      for (int i = 0; i < 3; ++i) f.v[i] = v[i];
      f.d = k[0] + k[1] + k[2];
      model[key] = faces.insert(f);
    }
    ASSERT_EQ(faces.size(), model.size());
  }
  for (const auto& [key, idx] : model) {
    const uint32_t k[3] = {key[0], key[1], key[2]};
    EXPECT_EQ(faces.find(k), idx);
  }
}

TEST(RingQueue, IsFifoAcrossGrowth) {
  RingQueue<int> q;
  int next_in = 0, next_out = 0;
  std::mt19937 rng(3);
  for (int step = 0; step < 100000; ++step) {
    if (rng() % 3 != 0 || q.empty()) {
      q.push_back(next_in++);
    } else {
      ASSERT_EQ(q.front(), next_out++);
      q.pop_front();
    }
    ASSERT_EQ(q.size(), static_cast<size_t>(next_in - next_out));
  }
  q.clear();
  EXPECT_TRUE(q.empty());
}

}  // namespace
}  // namespace gtn
