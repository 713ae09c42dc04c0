// collide(a, b, PairCache&): on random pose sequences with small motions the
// same hits as collide(a, b), fewer box tests, and a cache that is never
// trusted beyond what it can prove.
#include <gtest/gtest.h>

#include <random>

#include "octbake/collide.h"

#include "seeded_random.h"

namespace octbake {
namespace {

using test::random_rotation;
using test::uniform01;

#if defined(__SANITIZE_ADDRESS__) || !defined(NDEBUG)
constexpr int kSequences = 40;
#else
constexpr int kSequences = 120;
#endif

ObjectTree random_tree(std::mt19937& rng, int depth) {
  std::vector<std::vector<uint8_t>> masks = test::random_masks(rng, depth);
  const Eigen::Vector3d size(0.5 + uniform01(rng), 0.5 + uniform01(rng), 0.5 + uniform01(rng));
  OctreeMasks m{{-0.5 * size, 0.5 * size}, std::move(masks)};
  TreeInfo info;
  info.bounds = m.bounds;
  info.depth = m.depth();
  return ObjectTree(std::move(info), std::move(m));
}

bool occupied(const ObjectTree& t, int depth, const BoxCoord& c) {
  for (const BoxCoord& x : t.masks().boxes(depth))
    if (x == c) return true;
  return false;
}

TEST(PairCache, SameHitsFewerBoxTestsOnSmallMotions) {
  std::mt19937 rng(41);
  uint64_t with_cache = 0, without = 0;
  int hits = 0, steps = 0, cached_proofs = 0;
  for (int seq = 0; seq < kSequences; ++seq) {
    const int depth = 3 + int(rng() % 3);
    const ObjectTree ta = random_tree(rng, depth), tb = random_tree(rng, depth);
    Pose pa, pb;
    pa.rotation = random_rotation(rng);
    pb.rotation = random_rotation(rng);
    pb.position = 1.1 * (random_rotation(rng) * Eigen::Vector3d::UnitX());
    const Eigen::Vector3d velocity = 0.01 * (random_rotation(rng) * Eigen::Vector3d::UnitX());
    const Eigen::Quaterniond spin(Eigen::AngleAxisd(0.01, random_rotation(rng) * Eigen::Vector3d::UnitX()));
    PairCache cache;
    for (int frame = 0; frame < 40; ++frame) {
      pb.position += velocity;
      pb.rotation = (spin * pb.rotation).normalized();
      const PlacedTree a{&ta, pa, depth}, b{&tb, pb, depth};
      const bool was_full = cache.tree_a != nullptr;
      const PairTest plain = collide(a, b), cached = collide(a, b, cache);
      ASSERT_EQ(cached.hit, plain.hit) << "sequence " << seq << " frame " << frame;
      if (cached.hit) {
        // The cache now holds the proving pair: real, occupied, overlapping.
        ASSERT_EQ(cache.tree_a, &ta);
        ASSERT_EQ(cache.tree_b, &tb);
        ASSERT_EQ(cache.depth_a, depth);
        ASSERT_TRUE(occupied(ta, depth, cache.leaf.a) && occupied(tb, depth, cache.leaf.b));
        std::vector<LeafPair> all;
        collide_all(a, b, all);
        bool listed = false;
        for (const LeafPair& p : all) listed |= p.a == cache.leaf.a && p.b == cache.leaf.b;
        ASSERT_TRUE(listed) << "sequence " << seq << " frame " << frame;
        cached_proofs += was_full && cached.box_tests == 1;
      } else {
        ASSERT_EQ(cache.tree_a, nullptr) << "a miss empties the cache";
      }
      with_cache += cached.box_tests;
      without += plain.box_tests;
      hits += plain.hit;
      ++steps;
    }
  }
  EXPECT_GT(hits, steps * 3 / 10) << "of " << steps;
  EXPECT_LT(hits, steps * 7 / 10) << "of " << steps;
  EXPECT_GT(cached_proofs, hits / 2) << "the cached pair usually still proves the hit";
  EXPECT_LT(2 * with_cache, without) << with_cache << " vs " << without << " box tests";
}

TEST(PairCache, OnlyAValidCacheIsTried) {
  std::mt19937 rng(42);
  const ObjectTree ta = random_tree(rng, 4), tb = random_tree(rng, 4), other = random_tree(rng, 4);
  Pose pb;
  pb.position = {0.3, 0.2, 0.1};
  const PlacedTree a{&ta, Pose{}, 4}, b{&tb, pb, 4};
  const PairTest plain = collide(a, b);
  ASSERT_TRUE(plain.hit);

  PairCache good;
  ASSERT_TRUE(collide(a, b, good).hit);
  const PairTest again = collide(a, b, good);
  EXPECT_TRUE(again.hit);
  EXPECT_EQ(again.box_tests, 1u) << "the cached pair proves it alone";

  // Another tree, other depths, an unoccupied or out-of-range box: not tried.
  for (PairCache stale : {PairCache{&other, &tb, 4, 4, good.leaf}, PairCache{&ta, &tb, 3, 4, good.leaf},
                          PairCache{&ta, &tb, 4, 4, {{16, 0, 0}, good.leaf.b}}}) {
    const PairTest r = collide(a, b, stale);
    EXPECT_TRUE(r.hit);
    EXPECT_EQ(r.box_tests, plain.box_tests);
  }
  BoxCoord empty{0, 0, 0};
  for (uint32_t i = 0; i < 16 * 16 * 16 && occupied(ta, 4, empty); ++i) empty = {i % 16, (i / 16) % 16, i / 256};
  ASSERT_FALSE(occupied(ta, 4, empty));
  PairCache unoccupied{&ta, &tb, 4, 4, {empty, good.leaf.b}};
  EXPECT_EQ(collide(a, b, unoccupied).box_tests, plain.box_tests);

  // A real pair that no longer overlaps costs one test, then the full descent.
  Pose far = pb;
  far.position.x() += 0.05;
  PairCache moved = good;
  const PlacedTree b_far{&tb, far, 4};
  const PairTest fresh = collide(a, b_far);
  std::vector<LeafPair> all;
  collide_all(a, b_far, all);
  bool still = false;
  for (const LeafPair& p : all) still |= p.a == good.leaf.a && p.b == good.leaf.b;
  const PairTest r = collide(a, b_far, moved);
  EXPECT_EQ(r.hit, fresh.hit);
  if (!still) {
    EXPECT_EQ(r.box_tests, fresh.box_tests + 1);
  }
}

TEST(PairCache, NeverAFalseHit) {
  std::mt19937 rng(43);
  const ObjectTree ta = random_tree(rng, 4), tb = random_tree(rng, 4);
  Pose pb;
  pb.position = {0.3, 0.2, 0.1};
  const PlacedTree a{&ta, Pose{}, 4};
  PairCache cache;
  ASSERT_TRUE(collide(a, {&tb, pb, 4}, cache).hit);
  pb.position = {5, 0, 0};  // far apart now: the cached pair must not count
  const PairTest r = collide(a, {&tb, pb, 4}, cache);
  EXPECT_FALSE(r.hit);
  EXPECT_EQ(r.box_tests, 2u);  // the cached pair, then the roots
  EXPECT_EQ(cache.tree_a, nullptr);
}

}  // namespace
}  // namespace octbake
