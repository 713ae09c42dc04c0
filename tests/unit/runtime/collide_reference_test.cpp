// The fast descent against the plain scalar reference kept beside it: on
// random trees and poses (sizes up to 1000x apart, flat trees, far offsets)
// the same hit at every depth pair and, from collide_all, the same set of
// overlapping leaf pairs; and every build of the box-test kernel the CPU has
// gives identical results, counts included. And collide()'s separation
// after a miss keeps the miss under every translation shorter than it.
#include <gtest/gtest.h>

#include <algorithm>
#include <numbers>
#include <random>
#include <string>
#include <tuple>

#include "octbake/collide.h"

#include "seeded_random.h"

namespace octbake {
namespace {

using test::random_rotation;
using test::uniform01;

#if defined(__SANITIZE_ADDRESS__) || !defined(NDEBUG)
constexpr int kRuns = 40;
#else
constexpr int kRuns = 300;
#endif

// Each child present with probability 3/4 (a box may end up with none); one
// in eight trees is flat (zero thickness in z).
// `unit`: the tree's size in its own coordinates.
ObjectTree random_tree(std::mt19937& rng, int depth, double unit = 1) {
  std::vector<std::vector<uint8_t>> masks = test::random_masks(rng, depth);
  Eigen::Vector3d size(0.5 + uniform01(rng), 0.5 + uniform01(rng), 0.5 + uniform01(rng));
  if (rng() % 8 == 0) size.z() = 0;
  size *= unit;
  const Eigen::Vector3d lo = -0.5 * size + 0.2 * unit * Eigen::Vector3d(uniform01(rng), uniform01(rng), uniform01(rng));
  OctreeMasks m{{lo, lo + size}, std::move(masks)};
  TreeInfo info;
  info.bounds = m.bounds;
  info.depth = m.depth();
  return ObjectTree(std::move(info), std::move(m));
}

auto key(const LeafPair& p) { return std::tuple(p.a.x, p.a.y, p.a.z, p.b.x, p.b.y, p.b.z); }

std::vector<LeafPair> sorted(std::vector<LeafPair> v) {
  std::sort(v.begin(), v.end(), [](const LeafPair& x, const LeafPair& y) { return key(x) < key(y); });
  return v;
}

// A random pair: B's size 1/1000..1 of A's (log-uniform), placed so that
// about half the pairs touch; far from the origin one time in four.
std::pair<Pose, Pose> random_poses(std::mt19937& rng) {
  Pose a, b;
  const Eigen::Vector3d base = rng() % 4 == 0 ? Eigen::Vector3d(1e7, -1e7, 1e7) : Eigen::Vector3d(0, 0, 0);
  a.rotation = random_rotation(rng);
  b.rotation = random_rotation(rng);
  a.scale = 0.5 + uniform01(rng);
  b.scale = a.scale * std::pow(1000.0, -uniform01(rng));
  a.position = base;
  // Small ones go near A's boundary (where the trees decide), large ones anywhere close.
  const Eigen::Vector3d dir = random_rotation(rng) * Eigen::Vector3d::UnitX();
  b.position = base + a.scale * (0.3 + 0.6 * uniform01(rng)) * dir;
  return {a, b};
}

TEST(CollideReference, SameHitsAndLeafPairsAtEveryDepthPair) {
  std::mt19937 rng(31);
  int hits = 0, cases = 0;
  for (int run = 0; run < kRuns; ++run) {
    const int depth_a = 1 + int(rng() % 4), depth_b = 1 + int(rng() % 4);
    const ObjectTree ta = random_tree(rng, depth_a), tb = random_tree(rng, depth_b);
    const auto [pa, pb] = random_poses(rng);
    for (int da = 0; da <= depth_a; ++da)
      for (int db = 0; db <= depth_b; ++db) {
        const PlacedTree a{&ta, pa, da}, b{&tb, pb, db};
        const PairTest fast = collide(a, b), ref = collide_reference(a, b);
        ASSERT_EQ(fast.hit, ref.hit) << "run " << run << " depths " << da << "-" << db;
        std::vector<LeafPair> all_fast, all_ref;
        collide_all(a, b, all_fast);
        collide_all_reference(a, b, all_ref);
        const auto fast_set = sorted(all_fast), ref_set = sorted(all_ref);
        ASSERT_EQ(fast_set.size(), ref_set.size()) << "run " << run << " depths " << da << "-" << db;
        for (size_t i = 0; i < fast_set.size(); ++i) ASSERT_EQ(key(fast_set[i]), key(ref_set[i]));
        hits += fast.hit;
        ++cases;
      }
  }
  EXPECT_GT(hits, cases * 3 / 10) << "of " << cases;
  EXPECT_LT(hits, cases * 7 / 10) << "of " << cases;
}

TEST(CollideReference, EveryKernelBuildGivesTheSameBits) {
  std::vector<BoxKernel> kernels;
  for (const BoxKernel k : {BoxKernel::portable, BoxKernel::avx2, BoxKernel::avx512})
    if (use_box_kernel(k)) kernels.push_back(k);
  ASSERT_TRUE(use_box_kernel(BoxKernel::best));
  ASSERT_FALSE(kernels.empty());
  std::mt19937 rng(32);
  int hits = 0;
  for (int run = 0; run < kRuns; ++run) {
    const int depth_a = 1 + int(rng() % 4), depth_b = 1 + int(rng() % 4);
    const ObjectTree ta = random_tree(rng, depth_a), tb = random_tree(rng, depth_b);
    const auto [pa, pb] = random_poses(rng);
    const PlacedTree a{&ta, pa, depth_a}, b{&tb, pb, depth_b};
    std::vector<PairTest> results;
    std::vector<std::vector<LeafPair>> leaves;
    for (const BoxKernel k : kernels) {
      ASSERT_TRUE(use_box_kernel(k));
      results.push_back(collide(a, b));
      leaves.emplace_back();
      collide_all(a, b, leaves.back());
    }
    ASSERT_TRUE(use_box_kernel(BoxKernel::best));
    for (size_t k = 1; k < results.size(); ++k) {
      ASSERT_EQ(results[k].hit, results[0].hit) << "run " << run;
      ASSERT_EQ(results[k].box_tests, results[0].box_tests) << "run " << run;
      ASSERT_EQ(key(results[k].leaf), key(results[0].leaf)) << "run " << run;
      ASSERT_EQ(leaves[k].size(), leaves[0].size()) << "run " << run;
      for (size_t i = 0; i < leaves[k].size(); ++i) ASSERT_EQ(key(leaves[k][i]), key(leaves[0][i]));  // same order
    }
    hits += results[0].hit;
  }
  EXPECT_GT(hits, kRuns * 3 / 10);
  EXPECT_LT(hits, kRuns * 7 / 10);
}

// collide(a, b) in every kernel build this CPU runs: the same hit, box tests
// and leaf pair, and a hit wherever the scalar reference finds one. `hit`:
// the hit.
void expect_builds_agree(const PlacedTree& a, const PlacedTree& b, int run, bool& hit) {
  std::vector<PairTest> results;
  for (const BoxKernel k : {BoxKernel::portable, BoxKernel::avx2, BoxKernel::avx512})
    if (use_box_kernel(k)) results.push_back(collide(a, b));
  ASSERT_TRUE(use_box_kernel(BoxKernel::best));
  for (size_t k = 1; k < results.size(); ++k) {
    ASSERT_EQ(results[k].hit, results[0].hit) << "run " << run;
    ASSERT_EQ(results[k].box_tests, results[0].box_tests) << "run " << run;
    ASSERT_EQ(key(results[k].leaf), key(results[0].leaf)) << "run " << run;
  }
  if (collide_reference(a, b).hit) {
    ASSERT_TRUE(results[0].hit) << "run " << run;
  }
  hit = results[0].hit;
}

// Near-axis-aligned rotations (angles 1e-320..1e-270 rad) and B up to 1e-300
// times A's size give child offsets near and below the subnormal range, where
// a product with 2^-d may round: every build still gives the same bits (the
// AVX-512 build fuses those products with the sums), and no pair the scalar
// reference finds touching is missed.
TEST(CollideReference, EveryKernelBuildAgreesOnSubnormalOffsets) {
  std::mt19937 rng(33);
  const auto tiny_rotation = [&] {
    const double angle = std::pow(10.0, -270 - 50 * uniform01(rng));
    return Eigen::Quaterniond(Eigen::AngleAxisd(angle, random_rotation(rng) * Eigen::Vector3d::UnitX()));
  };
  int hits = 0;
  for (int run = 0; run < kRuns; ++run) {
    const int depth_a = 1 + int(rng() % 4), depth_b = 1 + int(rng() % 4);
    const ObjectTree ta = random_tree(rng, depth_a), tb = random_tree(rng, depth_b);
    Pose pa, pb;
    pa.rotation = tiny_rotation();
    pb.rotation = tiny_rotation();
    pb.scale = run % 2 == 0 ? std::pow(10.0, -300 * uniform01(rng)) : 0.5 + uniform01(rng);
    pb.position = Eigen::Vector3d(uniform01(rng), uniform01(rng), uniform01(rng)) - Eigen::Vector3d::Constant(0.5);
    const PlacedTree a{&ta, pa, depth_a}, b{&tb, pb, depth_b};
    bool hit = false;
    ASSERT_NO_FATAL_FAILURE(expect_builds_agree(a, b, run, hit));
    hits += hit;
  }
  EXPECT_GT(hits, 0);
  EXPECT_LT(hits, kRuns);
}

// Trees whose own coordinates are subnormal or nearly so (sizes 1e-300 to
// 1e-315): the children's offsets round differently in the fused builds, and
// every descent visits children in its nearest-first order (all overlap),
// yet every build gives the same hits, box tests and leaf pairs, and no pair
// the scalar reference finds touching is missed.
TEST(CollideReference, EveryKernelBuildAgreesOnSubnormalTrees) {
  std::mt19937 rng(34);
  int hits = 0;
  for (int run = 0; run < kRuns; ++run) {
    const int depth_a = 1 + int(rng() % 5), depth_b = 1 + int(rng() % 5);
    const double unit = std::pow(10.0, -300 - 15 * uniform01(rng));
    const ObjectTree ta = random_tree(rng, depth_a, unit), tb = random_tree(rng, depth_b, unit);
    Pose pa, pb;
    pa.rotation = random_rotation(rng);
    pb.rotation = run % 2 == 0 ? pa.rotation : random_rotation(rng);
    pb.scale = 0.5 + uniform01(rng);
    pb.position =
        unit * (Eigen::Vector3d(uniform01(rng), uniform01(rng), uniform01(rng)) - Eigen::Vector3d::Constant(0.5));
    const PlacedTree a{&ta, pa, depth_a}, b{&tb, pb, depth_b};
    bool hit = false;
    ASSERT_NO_FATAL_FAILURE(expect_builds_agree(a, b, run, hit));
    hits += hit;
  }
  // The padding's floor (2^-900) dwarfs these trees: every pair touches.
  EXPECT_EQ(hits, kRuns);
}

// Pairs that share an axis exactly (both turned about the same world axis,
// unturned, or a quarter turn apart, as upright objects that only yaw):
// collide() then tests the face axes alone (use_shared_axis_shortcut). At
// every depth pair, on the same random trees and placements as above, it
// gives what all fifteen axes give (hit, box tests, leaf pair, collide_all's
// leaf pairs) and the scalar reference's hits, in every kernel build.
TEST(CollideReference, SharedAxisPairsGiveWhatAllFifteenAxesGive) {
  std::mt19937 rng(35);
  int hits = 0, cases = 0;
  const auto turn = [&](int axis) {
    const int kind = int(rng() % 4);  // 0: none, 1: a quarter turn, else any angle
    const double angle = kind == 0 ? 0 : kind == 1 ? std::numbers::pi / 2 * double(1 + rng() % 3)
                                                   : 2 * std::numbers::pi * uniform01(rng);
    return Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d::Unit(axis)));
  };
  for (int run = 0; run < kRuns; ++run) {
    const int depth_a = 1 + int(rng() % 4), depth_b = 1 + int(rng() % 4);
    const ObjectTree ta = random_tree(rng, depth_a), tb = random_tree(rng, depth_b);
    auto [pa, pb] = random_poses(rng);
    const int axis = int(rng() % 3);
    pa.rotation = turn(axis);
    pb.rotation = turn(axis);
    for (int da = 0; da <= depth_a; ++da)
      for (int db = 0; db <= depth_b; ++db) {
        const PlacedTree a{&ta, pa, da}, b{&tb, pb, db};
        const PairTest faces = collide(a, b), ref = collide_reference(a, b);
        std::vector<LeafPair> all_faces, all_fifteen;
        collide_all(a, b, all_faces);
        use_shared_axis_shortcut(false);
        const PairTest fifteen = collide(a, b);
        collide_all(a, b, all_fifteen);
        use_shared_axis_shortcut(true);
        const std::string at =
            "run " + std::to_string(run) + " depths " + std::to_string(da) + "-" + std::to_string(db);
        ASSERT_EQ(faces.hit, ref.hit) << at;
        ASSERT_EQ(faces.hit, fifteen.hit) << at;
        ASSERT_EQ(faces.box_tests, fifteen.box_tests) << at;
        ASSERT_EQ(key(faces.leaf), key(fifteen.leaf)) << at;
        ASSERT_EQ(all_faces.size(), all_fifteen.size()) << at;
        for (size_t i = 0; i < all_faces.size(); ++i) ASSERT_EQ(key(all_faces[i]), key(all_fifteen[i])) << at;
        hits += faces.hit;
        ++cases;
      }
    bool hit = false;
    ASSERT_NO_FATAL_FAILURE(expect_builds_agree({&ta, pa, depth_a}, {&tb, pb, depth_b}, run, hit));
  }
  EXPECT_GT(hits, cases * 3 / 10) << "of " << cases;
  EXPECT_LT(hits, cases * 7 / 10) << "of " << cases;
}

// A small object against a large one: the larger tree splits first, so the
// fast descent needs far fewer box tests than the simultaneous one.
TEST(CollideReference, SmallAgainstLargeTakesFewerBoxTests) {
  std::mt19937 rng(33);
  uint64_t fast_tests = 0, ref_tests = 0;
  int hits = 0;
  const int runs = 150;  // cheap: one depth pair per run
  for (int run = 0; run < runs; ++run) {
    const ObjectTree large = random_tree(rng, 5), small = random_tree(rng, 5);
    Pose pa, pb;
    pa.rotation = random_rotation(rng);
    pb.rotation = random_rotation(rng);
    pb.scale = 1.0 / 400;
    pb.position = 0.6 * Eigen::Vector3d(uniform01(rng) - 0.5, uniform01(rng) - 0.5, uniform01(rng) - 0.5);
    const PlacedTree a{&large, pa, 5}, b{&small, pb, 5};
    const PairTest fast = collide(a, b), ref = collide_reference(a, b);
    ASSERT_EQ(fast.hit, ref.hit) << "run " << run;
    if (!fast.hit) continue;
    ++hits;
    fast_tests += fast.box_tests;
    ref_tests += ref.box_tests;
  }
  ASSERT_GT(hits, 10) << "of " << runs;  // sparse random trees: a tiny object often falls in a gap
  EXPECT_LT(5 * fast_tests, ref_tests) << fast_tests << " vs " << ref_tests << " box tests over " << hits << " hits";
}

// collide()'s separation after a miss: B translated by less than it, along
// each of the pair's fifteen box axes (where the binding box pair is closest
// to touching) and random directions, both ways, is still a miss, in every
// kernel build; the same hits and counts as collide(); and most misses get a
// margin (it is not 0 all the time).
TEST(CollideReference, SeparationKeepsTheMissUnderEveryTranslationShorterThanIt) {
  std::vector<BoxKernel> kernels;
  for (const BoxKernel k : {BoxKernel::portable, BoxKernel::avx2, BoxKernel::avx512})
    if (use_box_kernel(k)) kernels.push_back(k);
  std::mt19937 rng(36);
  int misses = 0, with_margin = 0, moves = 0;
  for (int run = 0; run < kRuns; ++run) {
    const int depth_a = 1 + int(rng() % 4), depth_b = 1 + int(rng() % 4);
    const ObjectTree ta = random_tree(rng, depth_a), tb = random_tree(rng, depth_b);
    const auto [pa, pb] = random_poses(rng);
    const BoxKernel kernel = kernels[size_t(run) % kernels.size()];
    ASSERT_TRUE(use_box_kernel(kernel));
    const Eigen::Matrix3d ra = pa.rotation.toRotationMatrix(), rb = pb.rotation.toRotationMatrix();
    std::vector<Eigen::Vector3d> dirs;
    for (int i = 0; i < 3; ++i) {
      dirs.push_back(ra.col(i));
      dirs.push_back(rb.col(i));
      for (int j = 0; j < 3; ++j)
        if (const Eigen::Vector3d c = ra.col(i).cross(rb.col(j)); c.norm() > 1e-6) dirs.push_back(c.normalized());
    }
    for (int k = 0; k < 4; ++k) dirs.push_back(random_rotation(rng) * Eigen::Vector3d::UnitX());
    for (int da = 0; da <= depth_a; ++da)
      for (int db = 0; db <= depth_b; ++db) {
        const PlacedTree a{&ta, pa, da}, b{&tb, pb, db};
        double separation = -1;
        const PairTest with = collide(a, b, separation), plain = collide(a, b);
        const std::string at =
            "run " + std::to_string(run) + " depths " + std::to_string(da) + "-" + std::to_string(db);
        ASSERT_EQ(with.hit, plain.hit) << at;
        ASSERT_EQ(with.box_tests, plain.box_tests) << at;
        ASSERT_EQ(key(with.leaf), key(plain.leaf)) << at;
        if (with.hit) {
          ASSERT_EQ(separation, 0) << at;
          continue;
        }
        ++misses;
        ASSERT_GE(separation, 0) << at;
        if (!(separation > 0) || !std::isfinite(separation)) continue;
        ++with_margin;
        for (const Eigen::Vector3d& dir : dirs)
          for (const double sign : {-1.0, 1.0})
            for (const double share : {0.999999, 0.5}) {
              PlacedTree moved = b;
              moved.pose.position += sign * share * separation * dir;
              ASSERT_FALSE(collide(a, moved).hit) << at << " moved by " << share << " of " << separation;
              ++moves;
            }
      }
  }
  ASSERT_TRUE(use_box_kernel(BoxKernel::best));
  EXPECT_GT(with_margin, misses * 3 / 4) << "of " << misses << " misses";
  EXPECT_GT(moves, 1000);
}

}  // namespace
}  // namespace octbake
