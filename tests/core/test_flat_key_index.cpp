// FlatKeyIndex / FlatKeySet against std::unordered_map: the same answers for random packed voxel
// keys, through the table's growth, for present, absent and repeated keys.
#include <gtest/gtest.h>

#include <random>
#include <unordered_map>
#include <unordered_set>

#include "mmlio/core/flat_key_index.hpp"
#include "mmlio/core/voxel_key.hpp"

namespace mmlio {

TEST(FlatKeyIndex, AnswersAsAnUnorderedMapThroughGrowth) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> axis(-200, 200);
  FlatKeyIndex index;
  std::unordered_map<std::uint64_t, std::uint32_t> reference;
  for (int i = 0; i < 20000; ++i) {
    const std::uint64_t key = packVoxelKey(axis(rng), axis(rng), axis(rng) / 50);
    const auto value = static_cast<std::uint32_t>(reference.size());
    const auto [got, added] = index.insert(key, value);
    const auto [it, ref_added] = reference.emplace(key, value);
    ASSERT_EQ(added, ref_added);
    ASSERT_EQ(got, it->second);
  }
  EXPECT_EQ(index.size(), reference.size());
  EXPECT_GT(reference.size(), 4096u);  // grown several times past the initial 1024 slots
  for (const auto& [key, value] : reference) ASSERT_EQ(index.find(key), value);
  for (int i = 0; i < 1000; ++i) {
    const std::uint64_t key = packVoxelKey(axis(rng) + 1000, axis(rng), 0);  // never inserted
    ASSERT_EQ(index.find(key), FlatKeyIndex::kNone);
  }
  index.clear();
  EXPECT_TRUE(index.empty());
  EXPECT_EQ(index.find(reference.begin()->first), FlatKeyIndex::kNone);
}

// reset() keeps (or, after a small fill, gives back) the slots; either way the next fill must
// answer as a fresh index does, with none of the earlier keys left behind.
TEST(FlatKeyIndex, ResetEmptiesItForARefillOfAnySize) {
  FlatKeyIndex index;
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> axis(-300, 300);
  for (const int keys : {20000, 20000, 50, 3000}) {
    index.reset();
    EXPECT_TRUE(index.empty());
    std::unordered_map<std::uint64_t, std::uint32_t> reference;
    for (int i = 0; i < keys; ++i) {
      const std::uint64_t key = packVoxelKey(axis(rng), axis(rng), axis(rng));
      const auto [got, added] = index.insert(key, static_cast<std::uint32_t>(reference.size()));
      const auto [it, ref_added] = reference.emplace(key, got);
      ASSERT_EQ(added, ref_added);
      ASSERT_EQ(got, it->second);
    }
    EXPECT_EQ(index.size(), reference.size());
    for (const auto& [key, value] : reference) ASSERT_EQ(index.find(key), value);
    for (int i = 0; i < 200; ++i) ASSERT_EQ(index.find(packVoxelKey(axis(rng) + 1000, 0, 0)), FlatKeyIndex::kNone);
  }
}

TEST(FlatKeyIndex, SetInsertsOnceAndFindsItsKeys) {
  FlatKeySet set;
  EXPECT_TRUE(set.insert(packVoxelKey(0, 0, 0)));  // key 0 of the origin's neighbourhood is a valid key
  EXPECT_FALSE(set.insert(packVoxelKey(0, 0, 0)));
  EXPECT_TRUE(set.insert(packVoxelKey(-1, 2, -3)));
  EXPECT_TRUE(set.contains(packVoxelKey(-1, 2, -3)));
  EXPECT_FALSE(set.contains(packVoxelKey(1, 2, 3)));
  EXPECT_EQ(set.size(), 2u);
}

TEST(FlatKeyIndex, SetAnswersAsAnUnorderedSetThroughGrowthForAnyKey) {
  std::mt19937_64 rng(11);
  FlatKeySet set;
  std::unordered_set<std::uint64_t> reference;
  for (int i = 0; i < 20000; ++i) {
    // Every 64-bit key, the all-ones one (the free-slot marker) included, and many repeats.
    const std::uint64_t key = i % 1000 == 0 ? ~std::uint64_t{0} : rng() % 30000;
    ASSERT_EQ(set.insert(key), reference.insert(key).second) << key;
  }
  EXPECT_EQ(set.size(), reference.size());
  for (std::uint64_t key = 0; key < 40000; ++key) ASSERT_EQ(set.contains(key), reference.count(key) > 0) << key;
  EXPECT_TRUE(set.contains(~std::uint64_t{0}));
  set.clear();
  EXPECT_FALSE(set.contains(~std::uint64_t{0}));
  EXPECT_TRUE(set.empty());
}

}  // namespace mmlio
