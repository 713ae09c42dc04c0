// LevelCache: levels decoded exactly when first needed, bit-identical to a
// full load() with enough budget, the budget never exceeded with a small one,
// deterministic LRU eviction of the deepest levels.
#include "octbake/level_cache.h"

#include <gtest/gtest.h>

#include "baked_test_util.h"
#include "octbake/collide.h"
#include "seeded_random.h"

namespace octbake {
namespace {

// A pack of `n` random depth-6 trees, bytes kept alive by the fixture.
class Cache : public ::testing::Test {
 protected:
  void make(int n, uint32_t seed) {
    std::mt19937 rng(seed);
    for (int i = 0; i < n; ++i) {
      trees_.push_back(test::random_tree(rng, "t" + std::to_string(i), 6, i % 2 ? Compression::none : Compression::zstd));
    }
    bytes_ = encode_file(trees_, "v");
    Result<BakedFile> f = BakedFile::from_bytes(bytes_, "pack");
    ASSERT_TRUE(f.ok()) << f.error().message;
    file_ = std::make_unique<BakedFile>(std::move(f).value());
    for (int i = 0; i < n; ++i) {
      Result<ObjectTree> full = file_->load(i, 6);
      ASSERT_TRUE(full.ok());
      full_.push_back(std::move(full).value());
    }
  }
  // Bytes tree i holds at `depth`, computed from the masks, not the cache.
  uint64_t bytes_at(int i, int depth) const {
    uint64_t b = 0;
    for (int d = 0; d < depth; ++d) b += 5 * trees_[i].masks.masks[d].size();
    return b;
  }
  // The cache's trees are prefixes of the full ones, and bytes_held adds up.
  void expect_consistent(const LevelCache& cache) const {
    uint64_t held = 0;
    for (TreeId id = 0; id < cache.size(); ++id) {
      const ObjectTree& t = cache.tree(id);
      ASSERT_EQ(t.loaded_depth(), cache.held_depth(id));
      for (int d = 0; d < t.loaded_depth(); ++d) {
        ASSERT_EQ(t.masks().masks[d], full_[id].masks().masks[d]) << "tree " << id << " depth " << d;
        for (uint32_t i = 0; i < t.masks().masks[d].size(); ++i) {
          ASSERT_EQ(t.first_child(d, i), full_[id].first_child(d, i));
          ASSERT_EQ(t.first_children(d)[i], t.first_child(d, i));  // the array the pair test reads
        }
      }
      held += bytes_at(id, t.loaded_depth());
    }
    ASSERT_EQ(cache.stats().bytes_held, held);
  }
  std::vector<TreeToEncode> trees_;
  std::vector<uint8_t> bytes_;
  std::unique_ptr<BakedFile> file_;
  std::vector<ObjectTree> full_;
};

TEST_F(Cache, LevelsAreDecodedExactlyWhenFirstNeeded) {
  make(2, 3);
  const uint64_t before = file_->stats().levels_decoded;
  LevelCache cache;
  Result<TreeId> a = cache.add(*file_, 1);
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(*a, 0u);
  EXPECT_EQ(cache.held_depth(*a), 0);
  EXPECT_EQ(cache.baked_depth(*a), 6);
  EXPECT_EQ(cache.stats().decodes, 0u);
  EXPECT_EQ(cache.stats().bytes_held, 0u);
  EXPECT_EQ(cache.tree(*a).bounds(), full_[1].bounds());
  const ObjectTree* address = &cache.tree(*a);

  struct Step { int ask, want, decodes; };
  for (const Step s : {Step{0, 0, 0}, {2, 2, 2}, {2, 2, 2}, {1, 1, 2}, {4, 4, 4}, {99, 6, 6}, {6, 6, 6}}) {
    Result<int> got = cache.require(*a, s.ask);
    ASSERT_TRUE(got.ok()) << got.error().message;
    EXPECT_EQ(*got, s.want) << "ask " << s.ask;
    EXPECT_EQ(cache.stats().decodes, uint64_t(s.decodes)) << "ask " << s.ask;
    EXPECT_EQ(file_->stats().levels_decoded - before, uint64_t(s.decodes));
  }
  EXPECT_EQ(cache.held_depth(*a), 6);
  EXPECT_EQ(&cache.tree(*a), address);
  EXPECT_EQ(cache.tree(*a).masks(), full_[1].masks());
  EXPECT_EQ(cache.stats().bytes_held, bytes_at(1, 6));
  EXPECT_EQ(cache.stats().peak_bytes_held, bytes_at(1, 6));
  EXPECT_EQ(cache.stats().evictions, 0u);
  EXPECT_EQ(cache.stats().budget_clamps, 0u);
  // The same tree again is the same entry; another tree of the file is not.
  EXPECT_EQ(*cache.add(*file_, 1), *a);
  EXPECT_EQ(*cache.add(*file_, 0), 1u);
  EXPECT_EQ(cache.size(), 2u);
  EXPECT_EQ(cache.held_depth(1), 0);
  // Moving the cache keeps the trees where they are.
  LevelCache moved = std::move(cache);
  EXPECT_EQ(&moved.tree(*a), address);
}

// With an unlimited budget the streamed trees give the same pair tests, bit
// for bit, as fully loaded ones at every depth asked.
TEST_F(Cache, UnlimitedBudgetEqualsFullLoadBitForBit) {
  make(5, 7);
  LevelCache cache;
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(cache.add(*file_, i).ok());
  std::mt19937 rng(8);
  int hits = 0;
  const int pairs = 400;
  for (int k = 0; k < pairs; ++k) {
    const TreeId ia = rng() % 5, ib = rng() % 5;
    const int da = int(rng() % 7), db = int(rng() % 7);
    Result<int> ga = cache.require(ia, da), gb = cache.require(ib, db);
    ASSERT_TRUE(ga.ok() && gb.ok());
    ASSERT_EQ(*ga, da);
    ASSERT_EQ(*gb, db);
    Pose pa, pb;
    pa.rotation = test::random_rotation(rng);
    pb.rotation = test::random_rotation(rng);
    // Both bounds centred near the origin, B's a random offset away.
    pa.position = -(pa.rotation * (0.5 * (full_[ia].bounds().min + full_[ia].bounds().max)));
    pb.position = test::random_point(rng, -8, 8) -
                  pb.rotation * (0.5 * (full_[ib].bounds().min + full_[ib].bounds().max));
    const PairTest streamed = collide({&cache.tree(ia), pa, da}, {&cache.tree(ib), pb, db});
    const PairTest loaded = collide({&full_[ia], pa, da}, {&full_[ib], pb, db});
    ASSERT_EQ(streamed.hit, loaded.hit) << k;
    ASSERT_EQ(streamed.box_tests, loaded.box_tests) << k;
    if (loaded.hit) {
      ASSERT_EQ(streamed.leaf.a, loaded.leaf.a);
      ASSERT_EQ(streamed.leaf.b, loaded.leaf.b);
    }
    hits += loaded.hit;
  }
  expect_consistent(cache);
  EXPECT_EQ(cache.stats().evictions, 0u);
  EXPECT_EQ(cache.stats().budget_clamps, 0u);
  // Not vacuous: both outcomes are common.
  EXPECT_GT(hits, pairs * 3 / 10);
  EXPECT_LT(hits, pairs * 7 / 10);
}

TEST_F(Cache, SmallBudgetIsNeverExceeded) {
  make(6, 11);
  uint64_t largest = 0;
  for (int i = 0; i < 6; ++i) largest = std::max(largest, bytes_at(i, 6));
  const uint64_t budget = largest / 2;  // no tree fits whole
  LevelCache cache(budget);
  for (int i = 0; i < 6; ++i) ASSERT_TRUE(cache.add(*file_, i).ok());
  std::mt19937 rng(12);
  int clamped = 0;
  for (int k = 0; k < 500; ++k) {
    const TreeId id = rng() % 6;
    const int ask = int(rng() % 7);
    const uint64_t clamps = cache.stats().budget_clamps;
    Result<int> got = cache.require(id, ask);
    ASSERT_TRUE(got.ok());
    ASSERT_LE(cache.stats().bytes_held, budget) << k;
    ASSERT_LE(*got, ask);
    ASSERT_GE(cache.held_depth(id), *got);
    if (*got < ask) {
      // Clamped only when the next level would not fit even alone.
      ASSERT_EQ(cache.stats().budget_clamps, clamps + 1);
      ASSERT_GT(bytes_at(id, *got + 1), budget) << k;
      ++clamped;
    } else {
      ASSERT_EQ(cache.stats().budget_clamps, clamps);
    }
  }
  expect_consistent(cache);
  EXPECT_GT(cache.stats().evictions, 0u);
  EXPECT_GT(clamped, 0);
  EXPECT_EQ(uint64_t(clamped), cache.stats().budget_clamps);
  EXPECT_LE(cache.stats().peak_bytes_held, budget);
  EXPECT_GT(cache.stats().decodes, cache.stats().evictions);
}

// Eviction takes the deepest levels of the least recently used other tree,
// ties broken by TreeId, and only as many as needed.
TEST_F(Cache, EvictsDeepestLevelsOfTheLeastRecentlyUsed) {
  make(3, 17);
  const uint64_t budget = bytes_at(0, 6) + bytes_at(1, 6) + bytes_at(2, 4);
  LevelCache cache(budget);
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(cache.add(*file_, i).ok());
  ASSERT_EQ(*cache.require(0, 6), 6);
  ASSERT_EQ(*cache.require(1, 6), 6);
  ASSERT_EQ(*cache.require(2, 6), 6);  // tree 0 is the oldest: it pays
  EXPECT_EQ(cache.held_depth(1), 6);
  EXPECT_EQ(cache.held_depth(2), 6);
  int expect0 = 6;  // the deepest depth of tree 0 that still fits beside the others
  while (bytes_at(0, expect0) + bytes_at(1, 6) + bytes_at(2, 6) > budget) --expect0;
  EXPECT_EQ(cache.held_depth(0), expect0);
  EXPECT_EQ(cache.stats().evictions, uint64_t(6 - expect0));
  expect_consistent(cache);

  // Never-used trees are the oldest; among them the smaller id goes first.
  LevelCache fresh(bytes_at(0, 6) + bytes_at(1, 6));
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(fresh.add(*file_, i).ok());
  ASSERT_EQ(*fresh.require(1, 6), 6);
  ASSERT_EQ(*fresh.require(0, 6), 6);
  ASSERT_EQ(*fresh.require(2, 2), 2);  // 1 is older than 0
  EXPECT_EQ(fresh.held_depth(0), 6);
  EXPECT_LT(fresh.held_depth(1), 6);
}

TEST_F(Cache, ClampsToTheDeepestDepthThatFitsAlone) {
  make(1, 23);
  LevelCache cache(bytes_at(0, 4) + 1);
  const TreeId id = *cache.add(*file_, 0);
  EXPECT_EQ(*cache.require(id, 6), 4);
  EXPECT_EQ(cache.stats().budget_clamps, 1u);
  EXPECT_EQ(*cache.require(id, 3), 3);  // not clamped: held deeper
  EXPECT_EQ(cache.stats().budget_clamps, 1u);
  EXPECT_EQ(cache.held_depth(id), 4);

  LevelCache none(0);  // depth 0 costs nothing
  const TreeId z = *none.add(*file_, 0);
  EXPECT_EQ(*none.require(z, 0), 0);
  EXPECT_EQ(none.stats().budget_clamps, 0u);
  EXPECT_EQ(*none.require(z, 5), 0);
  EXPECT_EQ(none.stats().budget_clamps, 1u);
  EXPECT_EQ(none.stats().decodes, 0u);
  EXPECT_EQ(none.stats().bytes_held, 0u);
}

TEST_F(Cache, SetBudgetEvictsNowOldestFirst) {
  make(2, 29);
  LevelCache cache;
  ASSERT_TRUE(cache.add(*file_, 0).ok());
  ASSERT_TRUE(cache.add(*file_, 1).ok());
  ASSERT_EQ(*cache.require(1, 6), 6);
  ASSERT_EQ(*cache.require(0, 6), 6);
  cache.set_budget(bytes_at(0, 6));
  EXPECT_EQ(cache.budget(), bytes_at(0, 6));
  EXPECT_EQ(cache.held_depth(1), 0);  // the older tree goes entirely first
  EXPECT_EQ(cache.held_depth(0), 6);
  EXPECT_EQ(cache.stats().evictions, 6u);
  cache.set_budget(bytes_at(0, 2));  // now the most recent one must shrink too
  EXPECT_EQ(cache.held_depth(0), 2);
  EXPECT_EQ(cache.stats().evictions, 10u);
  expect_consistent(cache);
  cache.set_budget(0);
  EXPECT_EQ(cache.held_depth(0), 0);
  EXPECT_EQ(cache.stats().bytes_held, 0u);
}

TEST_F(Cache, BadArgumentsAreTypedErrors) {
  make(1, 31);
  LevelCache cache;
  Result<TreeId> bad = cache.add(*file_, 1);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, ErrorCode::invalid_argument);
  EXPECT_NE(bad.error().message.find("pack"), std::string::npos);
  EXPECT_EQ(cache.require(0, 1).error().code, ErrorCode::invalid_argument);
  const TreeId id = *cache.add(*file_, 0);
  EXPECT_EQ(cache.require(id, -1).error().code, ErrorCode::invalid_argument);
}

// A broken level 4: depths 0..3 stream fine, asking deeper fails with the
// decoder's error and leaves a consistent cache holding depth 3.
TEST(CacheErrors, BrokenLevelFailsAndKeepsWhatDecoded) {
  test::ForgedTree t = test::forged_from(test::full_masks(5), fb::Compression::Zstd);
  t.levels[4].data.assign(t.levels[4].data.size(), 0x5A);
  const std::vector<uint8_t> bytes = test::forge({t});
  Result<BakedFile> file = BakedFile::from_bytes(bytes, "mem");
  ASSERT_TRUE(file.ok()) << file.error().message;
  LevelCache cache;
  const TreeId id = *cache.add(*file, 0);
  EXPECT_EQ(*cache.require(id, 3), 3);
  Result<int> deeper = cache.require(id, 5);
  ASSERT_FALSE(deeper.ok());
  EXPECT_EQ(deeper.error().code, ErrorCode::decompress_failed);
  EXPECT_NE(deeper.error().message.find("level 4"), std::string::npos);
  EXPECT_EQ(cache.held_depth(id), 3);
  EXPECT_EQ(cache.stats().decodes, 3u);
  EXPECT_EQ(cache.stats().bytes_held, 5u * (1 + 8 + 64));
}

}  // namespace
}  // namespace octbake
