// Sharing read-only: several threads decode from one BakedFile (each through
// its own LevelCache, and by load()), and run collide() on trees loaded once
// and shared. Built and run under ThreadSanitizer by test.sh (ctest -L tsan);
// in the other builds it still checks that every thread gets the answers a
// single thread gets and that the shared counters add up.
#include <gtest/gtest.h>

#include <thread>

#include "octbake/collide.h"
#include "octbake/level_cache.h"
#include "seeded_random.h"
#include "unit/runtime/baked_test_util.h"

namespace octbake {
namespace {

constexpr int kTrees = 4, kThreads = 4;

struct Outcome {
  std::vector<uint64_t> answers;  // per pair: hit + 2 * box_tests, streamed and shared
  uint64_t levels_decoded = 0;    // by this thread's cache and load() calls
  bool operator==(const Outcome&) const = default;
};

// One thread's work: a cache with a small budget streams levels from `file`
// while pairs are tested both on its trees and on the shared full ones.
Outcome work(const BakedFile& file, const std::vector<ObjectTree>& shared, uint32_t seed, uint64_t budget) {
  Outcome out;
  LevelCache cache(budget);
  for (int i = 0; i < kTrees; ++i) {
    if (!cache.add(file, i).ok()) return out;
  }
  std::mt19937 rng(seed);
  for (int k = 0; k < 150; ++k) {
    const TreeId a = rng() % kTrees, b = rng() % kTrees;
    Result<int> ra = cache.require(a, int(rng() % 7));
    Result<int> rb = cache.require(b, int(rng() % 7));
    if (!ra || !rb) return out;
    Pose pa, pb;
    pa.rotation = test::random_rotation(rng);
    pb.rotation = test::random_rotation(rng);
    pb.position = test::random_point(rng, -15, 15);
    // require(b) may have evicted levels of a: test at what both still hold.
    const int da = std::min(*ra, cache.held_depth(a)), db = std::min(*rb, cache.held_depth(b));
    const PairTest streamed = collide({&cache.tree(a), pa, da}, {&cache.tree(b), pb, db});
    const PairTest full = collide({&shared[a], pa, 6}, {&shared[b], pb, 6});
    out.answers.push_back(streamed.hit + 2 * streamed.box_tests);
    out.answers.push_back(full.hit + 2 * full.box_tests);
    if (k % 25 == 0) {
      Result<ObjectTree> loaded = file.load(a, 3);
      if (!loaded) return out;
      out.levels_decoded += 3;
    }
    (void)file.stats();  // read while other threads count
  }
  out.levels_decoded += cache.stats().decodes;
  return out;
}

TEST(SharedRead, ThreadsDecodeAndCollideOnSharedFilesAndTrees) {
  std::mt19937 rng(41);
  std::vector<TreeToEncode> trees;
  for (int i = 0; i < kTrees; ++i) {
    trees.push_back(test::random_tree(rng, "t" + std::to_string(i), 6, i % 2 ? Compression::none : Compression::zstd));
  }
  const std::vector<uint8_t> bytes = encode_file(trees, "v");
  Result<BakedFile> file = BakedFile::from_bytes(bytes, "shared");
  ASSERT_TRUE(file.ok()) << file.error().message;
  std::vector<ObjectTree> shared;
  uint64_t largest = 0;
  for (int i = 0; i < kTrees; ++i) {
    shared.push_back(*file->load(i, 6));
    largest = std::max(largest, file->trees()[i].raw_bytes[6]);
  }
  const uint64_t budget = 5 * largest;  // about one deep tree: evictions all the time

  std::vector<Outcome> alone;
  for (int t = 0; t < kThreads; ++t) alone.push_back(work(*file, shared, 100 + t, budget));
  const uint64_t before = file->stats().levels_decoded;

  std::vector<Outcome> together(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] { together[t] = work(*file, shared, 100 + t, budget); });
  }
  for (std::thread& th : threads) th.join();

  uint64_t decoded = 0;
  for (int t = 0; t < kThreads; ++t) {
    ASSERT_EQ(together[t].answers.size(), 300u) << "thread " << t << " stopped early";
    EXPECT_EQ(together[t], alone[t]) << "thread " << t;
    decoded += together[t].levels_decoded;
  }
  EXPECT_EQ(file->stats().levels_decoded - before, decoded);
  EXPECT_GT(decoded, uint64_t(kThreads) * 150);  // the small budget made them re-decode
}

}  // namespace
}  // namespace octbake
