// collide / collide_all on hand-built trees: hand-checkable contacts, counts,
// symmetry, and the leaf pairs against a brute-force oriented-box test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <tuple>

#include "octbake/collide.h"

#if defined(__x86_64__)
#include <cpuid.h>
#endif

#include "seeded_random.h"

namespace octbake {
namespace {

using test::random_rotation;
using test::uniform01;

ObjectTree make_tree(const Aabb& bounds, std::vector<std::vector<uint8_t>> masks) {
  OctreeMasks m{bounds, std::move(masks)};
  TreeInfo info;
  info.bounds = bounds;
  info.depth = m.depth();
  return ObjectTree(std::move(info), std::move(m));
}

// Every box occupied down to `depth`.
ObjectTree full_tree(const Aabb& bounds, int depth) {
  std::vector<std::vector<uint8_t>> masks;
  for (int d = 0; d < depth; ++d) masks.emplace_back(size_t(1) << (3 * d), uint8_t{0xFF});
  return make_tree(bounds, std::move(masks));
}

// Each child present with probability 3/4 (a box may end up with none).
ObjectTree random_tree(std::mt19937& rng, int depth) {
  std::vector<std::vector<uint8_t>> masks = test::random_masks(rng, depth);
  const Eigen::Vector3d size(0.5 + uniform01(rng), 0.5 + uniform01(rng), 0.5 + uniform01(rng));
  const Eigen::Vector3d lo = -0.5 * size + 0.2 * Eigen::Vector3d(uniform01(rng), uniform01(rng), uniform01(rng));
  return make_tree({lo, lo + size}, std::move(masks));
}

const Aabb kUnit{{0, 0, 0}, {1, 1, 1}};
const Aabb kCentred{{-1, -1, -1}, {1, 1, 1}};

Pose at(Eigen::Vector3d p, Eigen::Quaterniond q = Eigen::Quaterniond::Identity(), double s = 1) {
  Pose pose;
  pose.position = p;
  pose.rotation = q;
  pose.scale = s;
  return pose;
}

// Independent reference: 15-axis separating test on world-space corners.
struct WorldBox {
  OrientedBox box;
  std::array<Eigen::Vector3d, 8> corners;
};

WorldBox world_box(const OrientedBox& o) {
  WorldBox w{o, {}};
  for (int k = 0; k < 8; ++k)
    w.corners[k] = o.center + o.axes * Eigen::Vector3d((k & 1 ? 1 : -1) * o.half[0], (k & 2 ? 1 : -1) * o.half[1],
                                                       (k & 4 ? 1 : -1) * o.half[2]);
  return w;
}

bool boxes_overlap(const WorldBox& a, const WorldBox& b) {
  std::array<Eigen::Vector3d, 15> axes;
  int n = 0;
  for (int i = 0; i < 3; ++i) {
    axes[n++] = a.box.axes.col(i);
    axes[n++] = b.box.axes.col(i);
    for (int j = 0; j < 3; ++j) axes[n++] = a.box.axes.col(i).cross(b.box.axes.col(j));
  }
  for (const auto& axis : axes) {
    if (axis.norm() < 1e-12) continue;
    double amin = INFINITY, amax = -INFINITY, bmin = INFINITY, bmax = -INFINITY;
    for (const auto& p : a.corners) amin = std::min(amin, p.dot(axis)), amax = std::max(amax, p.dot(axis));
    for (const auto& p : b.corners) bmin = std::min(bmin, p.dot(axis)), bmax = std::max(bmax, p.dot(axis));
    if (amax < bmin || bmax < amin) return false;
  }
  return true;
}

auto key(const LeafPair& p) { return std::tuple(p.a.x, p.a.y, p.a.z, p.b.x, p.b.y, p.b.z); }

TEST(Collide, RootsOnlyCountOneTest) {
  const ObjectTree t = full_tree(kUnit, 3);
  const PairTest hit = collide({&t, at({0.5, 0, 0}), 0}, {&t, at({0, 0, 0}), 0});
  EXPECT_TRUE(hit.hit);
  EXPECT_EQ(hit.box_tests, 1u);
  const PairTest miss = collide({&t, at({2, 0, 0}), 3}, {&t, at({0, 0, 0}), 3});
  EXPECT_FALSE(miss.hit);
  EXPECT_EQ(miss.box_tests, 1u);
}

TEST(Collide, FirstLeafPairEndsTheDescent) {
  // Identical full trees at the same pose: the trees split in turn, all 8
  // children of each split are tested, and the first leaf pair ends it.
  const ObjectTree t = full_tree(kUnit, 3);
  const PairTest r = collide({&t, at({0, 0, 0}), 3}, {&t, at({0, 0, 0}), 3});
  EXPECT_TRUE(r.hit);
  EXPECT_EQ(r.box_tests, 1u + 6 * 8);  // root, then 3 splits per tree
  const PairTest one_side = collide({&t, at({0, 0, 0}), 0}, {&t, at({0, 0, 0}), 2});
  EXPECT_TRUE(one_side.hit);
  EXPECT_EQ(one_side.box_tests, 1u + 2 * 8);
  // The reference splits both at once and tests one pair at a time.
  EXPECT_EQ(collide_reference({&t, at({0, 0, 0}), 3}, {&t, at({0, 0, 0}), 3}).box_tests, 4u);
}

TEST(Collide, LargerBoxSplitsFirst) {
  // B is 64 times smaller than A: A splits to its leaves before B splits,
  // so with B inside one of A's boxes each split has one overlapping child.
  const ObjectTree t = full_tree(kUnit, 4);
  const PlacedTree a{&t, at({0, 0, 0}), 4};
  const PlacedTree b{&t, at({0.26, 0.26, 0.26}, Eigen::Quaterniond::Identity(), 1.0 / 64), 4};
  const PairTest r = collide(a, b);
  EXPECT_TRUE(r.hit);
  // Root, 4 splits of A (8 each), then B's root lies inside A's leaf: proved.
  EXPECT_EQ(r.box_tests, 1u + 4 * 8 + 1);
  EXPECT_EQ(collide(b, a).box_tests, r.box_tests);
  EXPECT_TRUE(collide_reference(a, b).hit);
}

TEST(Collide, AxisAlignedFacesTouchAtEveryDepth) {
  const ObjectTree t = full_tree(kUnit, 4);
  for (const double offset : {0.0, 1e7}) {
    const Eigen::Vector3d base(offset, -offset, offset);
    for (int da = 0; da <= 4; ++da)
      for (int db = 0; db <= 4; ++db) {
        const PlacedTree a{&t, at(base), da};
        EXPECT_TRUE(collide(a, {&t, at(base + Eigen::Vector3d(1, 0, 0)), db}).hit) << da << " " << db;
        EXPECT_TRUE(collide(a, {&t, at(base + Eigen::Vector3d(1, 1, 1)), db}).hit);  // corners meet
        EXPECT_FALSE(collide(a, {&t, at(base + Eigen::Vector3d(1 + 1e-6, 0, 0)), db}).hit);
        EXPECT_FALSE(collide(a, {&t, at(base + Eigen::Vector3d(0, -1 - 1e-6, 0.5)), db}).hit);
      }
  }
}

TEST(Collide, SparseTreesTouchOnlyWhereBoxesAre) {
  // A holds only its lowest corner octant; B only its highest.
  const ObjectTree a = make_tree(kUnit, {{0x01}});
  const ObjectTree b = make_tree(kUnit, {{0x80}});
  // B moved by (-0.5,-0.5,-0.5): its kept octant sits exactly on A's kept one.
  EXPECT_TRUE(collide({&a, at({0, 0, 0}), 1}, {&b, at({-0.5, -0.5, -0.5}), 1}).hit);
  // B moved by (0.5, 0, 0): the roots overlap, the kept octants are 0.5 apart.
  const PairTest r = collide({&a, at({0, 0, 0}), 1}, {&b, at({0.5, 0, 0}), 1});
  EXPECT_FALSE(r.hit);
  EXPECT_EQ(r.box_tests, 3u);  // roots, A's one child, B's one child
  EXPECT_TRUE(collide({&a, at({0, 0, 0}), 0}, {&b, at({0.5, 0, 0}), 1}).hit);
}

TEST(Collide, Rotated45Degrees) {
  const ObjectTree t = full_tree(kCentred, 3);
  const Eigen::Quaterniond q(Eigen::AngleAxisd(std::numbers::pi / 4, Eigen::Vector3d::UnitZ()));
  const double reach = 1 + std::sqrt(2.0);  // B's corner touches A's +x face
  for (int d = 0; d <= 3; ++d) {
    EXPECT_TRUE(collide({&t, at({0, 0, 0}), d}, {&t, at({reach - 1e-6, 0, 0}, q), d}).hit);
    EXPECT_FALSE(collide({&t, at({0, 0, 0}), d}, {&t, at({reach + 1e-6, 0, 0}, q), d}).hit);
    // Both rotated by the same 45 degrees about z: faces meet along the diagonal.
    const Eigen::Vector3d diag = q * Eigen::Vector3d(2, 0, 0);
    EXPECT_TRUE(collide({&t, at({0, 0, 0}, q), d}, {&t, at(diag, q), d}).hit);
    EXPECT_FALSE(collide({&t, at({0, 0, 0}, q), d}, {&t, at(diag * (1 + 1e-6), q), d}).hit);
    // Edge against edge: B rotated 45 degrees about x, sitting above A's top.
    const Eigen::Quaterniond qx(Eigen::AngleAxisd(std::numbers::pi / 4, Eigen::Vector3d::UnitX()));
    EXPECT_TRUE(collide({&t, at({0, 0, 0}), d}, {&t, at({0, reach - 1e-6, 0}, qx), d}).hit);
    EXPECT_FALSE(collide({&t, at({0, 0, 0}), d}, {&t, at({0, reach + 1e-6, 0}, qx), d}).hit);
  }
}

TEST(Collide, FlatTreeRestingOnABox) {
  const ObjectTree cube = full_tree(kUnit, 3);
  const ObjectTree quad = full_tree({{0, 0, 0}, {1, 1, 0}}, 3);  // zero thickness in z
  for (int d = 0; d <= 3; ++d) {
    EXPECT_TRUE(collide({&cube, at({0, 0, 0}), d}, {&quad, at({0.5, 0.5, 1}), d}).hit);
    EXPECT_FALSE(collide({&cube, at({0, 0, 0}), d}, {&quad, at({0.5, 0.5, 1 + 1e-6}), d}).hit);
    EXPECT_TRUE(collide({&quad, at({0, 0, 0}), d}, {&quad, at({0.5, 0.5, 0}), d}).hit);  // coplanar
  }
}

TEST(Collide, ScaleIsRelative) {
  const ObjectTree t = full_tree(kUnit, 2);
  for (const double s : {1e-4, 1.0, 1e4}) {
    EXPECT_TRUE(collide({&t, at({0, 0, 0}, {1, 0, 0, 0}, s), 2}, {&t, at({s, 0, 0}, {1, 0, 0, 0}, 2 * s), 2}).hit);
    EXPECT_FALSE(
        collide({&t, at({0, 0, 0}, {1, 0, 0, 0}, s), 2}, {&t, at({s * (1 + 1e-6), 0, 0}, {1, 0, 0, 0}, 2 * s), 2}).hit);
  }
}

// Dense trees overlapping over a wide region: levels of hundreds of box
// pairs, which collide_all expands in many batches (of up to 32 pairs, their
// children tested 64 to a word): still exactly the overlapping leaf pairs of a
// brute-force test, each once, in the same order from every build.
TEST(Collide, AllLeafPairsOfWideLevelsMatchBruteForce) {
  const ObjectTree ta = full_tree(kUnit, 4), tb = full_tree(kUnit, 3);
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()));
  const PlacedTree a{&ta, at({0, 0, 0}), 4}, b{&tb, at({0.43, 0.31, 0.17}, turn, 1.1), 3};
  std::vector<WorldBox> boxes_b;
  const std::vector<BoxCoord> leaves_b = tb.masks().boxes(3);
  for (const BoxCoord& cb : leaves_b) boxes_b.push_back(world_box(place(tb.masks().box_bounds(3, cb), b.pose)));
  std::vector<LeafPair> expected;
  for (const BoxCoord& ca : ta.masks().boxes(4)) {
    const WorldBox box_a = world_box(place(ta.masks().box_bounds(4, ca), a.pose));
    for (size_t j = 0; j < leaves_b.size(); ++j)
      if (boxes_overlap(box_a, boxes_b[j])) expected.push_back({ca, leaves_b[j]});
  }
  std::vector<LeafPair> found;
  const PairTest all = collide_all(a, b, found);
  EXPECT_TRUE(all.hit);
  // More leaf pairs than one batch's children can give: many batches.
  EXPECT_GT(found.size(), 4u * 256);
  auto by_key = [](const LeafPair& x, const LeafPair& y) { return key(x) < key(y); };
  std::vector<LeafPair> sorted_found = found;
  std::sort(expected.begin(), expected.end(), by_key);
  std::sort(sorted_found.begin(), sorted_found.end(), by_key);
  ASSERT_EQ(sorted_found.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) ASSERT_EQ(key(sorted_found[i]), key(expected[i])) << i;

  std::vector<LeafPair> found_ba;
  EXPECT_EQ(collide_all(b, a, found_ba).box_tests, all.box_tests);
  ASSERT_EQ(found_ba.size(), found.size());
  for (size_t i = 0; i < found.size(); ++i) ASSERT_EQ(key(found_ba[i]), key(LeafPair{found[i].b, found[i].a})) << i;
  for (const BoxKernel k : {BoxKernel::portable, BoxKernel::avx2, BoxKernel::avx512}) {
    if (!use_box_kernel(k)) continue;
    std::vector<LeafPair> again;
    const PairTest r = collide_all(a, b, again);
    ASSERT_TRUE(use_box_kernel(BoxKernel::best));
    EXPECT_EQ(r.box_tests, all.box_tests);
    ASSERT_EQ(again.size(), found.size());
    for (size_t i = 0; i < found.size(); ++i) ASSERT_EQ(key(again[i]), key(found[i])) << i;
  }
}

// Random trees and poses: collide_all finds exactly the overlapping leaf pairs
// of a brute-force test, collide agrees, and both orders give the same answer.
TEST(Collide, AllLeafPairsMatchBruteForce) {
  std::mt19937 rng(7);
  int hits = 0, runs = 0;
  for (int run = 0; run < 300; ++run) {
    const int depth_a = int(rng() % 4), depth_b = int(rng() % 4);
    const ObjectTree ta = random_tree(rng, depth_a), tb = random_tree(rng, depth_b);
    const double spread = 1.6;
    auto random_pose = [&] {
      return at({spread * (uniform01(rng) - 0.5), spread * (uniform01(rng) - 0.5), spread * (uniform01(rng) - 0.5)},
                random_rotation(rng), 0.5 + uniform01(rng));
    };
    const PlacedTree a{&ta, random_pose(), depth_a}, b{&tb, random_pose(), depth_b};

    const std::vector<BoxCoord> leaves_a = ta.masks().boxes(depth_a), leaves_b = tb.masks().boxes(depth_b);
    std::vector<WorldBox> boxes_b;
    for (const BoxCoord& cb : leaves_b) boxes_b.push_back(world_box(place(tb.masks().box_bounds(depth_b, cb), b.pose)));
    std::vector<LeafPair> expected;
    for (const BoxCoord& ca : leaves_a) {
      const WorldBox box_a = world_box(place(ta.masks().box_bounds(depth_a, ca), a.pose));
      for (size_t j = 0; j < leaves_b.size(); ++j)
        if (boxes_overlap(box_a, boxes_b[j])) expected.push_back({ca, leaves_b[j]});
    }

    std::vector<LeafPair> found, found_ba;
    const PairTest all = collide_all(a, b, found);
    const PairTest all_ba = collide_all(b, a, found_ba);
    auto by_key = [](const LeafPair& x, const LeafPair& y) { return key(x) < key(y); };
    std::sort(expected.begin(), expected.end(), by_key);
    std::sort(found.begin(), found.end(), by_key);
    ASSERT_EQ(found.size(), expected.size()) << "run " << run;
    for (size_t i = 0; i < found.size(); ++i) ASSERT_EQ(key(found[i]), key(expected[i])) << "run " << run;
    ASSERT_EQ(found_ba.size(), found.size());
    EXPECT_EQ(all.hit, !expected.empty());
    EXPECT_EQ(all.box_tests, all_ba.box_tests);

    const PairTest ab = collide(a, b), ba = collide(b, a);
    EXPECT_EQ(ab.hit, !expected.empty()) << "run " << run;
    EXPECT_EQ(ab.hit, ba.hit);
    EXPECT_EQ(ab.box_tests, ba.box_tests);
    EXPECT_LE(ab.box_tests, all.box_tests);
    if (ab.hit) {
      // The proving leaf pair is one of the overlapping ones, in argument
      // order, and the same pair whichever order the arguments come in.
      EXPECT_TRUE(std::binary_search(expected.begin(), expected.end(), ab.leaf, by_key)) << "run " << run;
      EXPECT_EQ(key(ab.leaf), key(LeafPair{ba.leaf.b, ba.leaf.a}));
    }
    hits += ab.hit;
    ++runs;
  }
  // Not vacuous: both outcomes are common.
  EXPECT_GT(hits, runs * 3 / 10);
  EXPECT_LT(hits, runs * 7 / 10);
}

// roots_apart is a safe shortcut: whenever it says apart, collide() ends at
// its root test with a miss at every depth pair, in both argument orders, and
// the unpadded root boxes are disjoint (independent test). Poses put the
// roots at gaps from -1e-3 to +1e-3 of their size along a face axis (the
// knife edge included), or anywhere near each other (every other run), with
// sizes 1e-3..1e3 apart, at the origin and 1e7.
TEST(Collide, RootsApartOnlyWhereCollideMissesAtItsRoot) {
  std::mt19937 rng(17);
  int apart = 0, knife_edge = 0, clear = 0, runs = 0;
  for (int run = 0; run < 4000; ++run) {
    const int depth_a = int(rng() % 4), depth_b = int(rng() % 4);
    const ObjectTree ta = random_tree(rng, depth_a), tb = random_tree(rng, depth_b);
    const double offset = run % 3 == 0 ? 1e7 : 0;
    const Eigen::Quaterniond qa = run % 4 == 0 ? Eigen::Quaterniond::Identity() : random_rotation(rng);
    const Eigen::Quaterniond qb = run % 4 == 1 ? qa : random_rotation(rng);
    const double sa = std::pow(10.0, -3 + 6 * uniform01(rng)), sb = sa * std::pow(10.0, -2.6 + 5.2 * uniform01(rng));
    PlacedTree a{&ta, at(Eigen::Vector3d::Constant(offset), qa, sa), depth_a};
    PlacedTree b{&tb, at(Eigen::Vector3d::Zero(), qb, sb), depth_b};
    // b's root just beyond (or just into) a's root along a's face axis `axis`.
    const OrientedBox ra = place(ta.bounds(), a.pose), rb0 = place(tb.bounds(), b.pose);
    const int axis = int(rng() % 3);
    const Eigen::Vector3d n = ra.axes.col(axis) * (rng() % 2 ? 1.0 : -1.0);
    const double reach_b = (rb0.axes.transpose() * n).cwiseAbs().dot(rb0.half);
    const double size = ra.half.maxCoeff() + rb0.half.maxCoeff();
    const double gaps[] = {1e-3, 1e-7, 1e-10, 1e-13, 0, -1e-13, -1e-10, -1e-3};
    const double gap = gaps[rng() % 8] * size;
    b.pose.position = ra.center + n * (ra.half[axis] + reach_b + gap) - rb0.center +
                      0.3 * size * (uniform01(rng) - 0.5) * ra.axes.col((axis + 1) % 3);
    const bool anywhere = run % 2 == 1;
    if (anywhere)
      b.pose.position = ra.center - rb0.center + size * Eigen::Vector3d(uniform01(rng) - 0.5, uniform01(rng) - 0.5,
                                                                         uniform01(rng) - 0.5);
    const bool roots_miss = !collide({&ta, a.pose, 0}, {&tb, b.pose, 0}).hit;
    if (roots_apart(a, b)) {
      ++apart;
      // Independently, relative to a's position (corners at 1e7 would round
      // more than the smallest gaps).
      const Pose rel_a = at(Eigen::Vector3d::Zero(), qa, sa), rel_b = at(b.pose.position - a.pose.position, qb, sb);
      EXPECT_FALSE(boxes_overlap(world_box(place(ta.bounds(), rel_a)), world_box(place(tb.bounds(), rel_b))))
          << "run " << run << " gap " << gap / size;
      for (int da = 0; da <= depth_a; ++da)
        for (int db = 0; db <= depth_b; ++db) {
          const PlacedTree pa{&ta, a.pose, da}, pb{&tb, b.pose, db};
          const PairTest ab = collide(pa, pb), ba = collide(pb, pa);
          ASSERT_TRUE(!ab.hit && ab.box_tests == 1 && !ba.hit && ba.box_tests == 1) << "run " << run;
        }
    } else {
      knife_edge += roots_miss;
      // A clear gap (a thousandth of the sizes) is always found.
      if (!anywhere && gap >= 1e-3 * size) ++clear, ADD_FAILURE() << "run " << run << ": a gap of " << gap << " not found";
    }
    ++runs;
  }
  // Not vacuous: most gaps are found, and collide() misses some roots that
  // roots_apart leaves to it (the gap within its margin, or on an edge axis).
  EXPECT_GT(apart, runs / 4);
  EXPECT_GT(knife_edge, 0);
  std::printf("apart %d of %d, left to collide() within the margin %d\n", apart, runs, knife_edge);
  EXPECT_EQ(clear, 0);
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
// XINUSE (XGETBV with ECX = 1, Intel SDM vol. 1, 13.6), where the CPU has it:
// bit 2 is set while the YMM registers' upper halves are not all zero, bit 6
// likewise for the ZMM registers' upper 256 bits.
std::optional<uint64_t> vector_state_in_use() {
  unsigned a, b, c, d;
  if (!__get_cpuid(1, &a, &b, &c, &d) || !(c & bit_OSXSAVE)) return std::nullopt;
  if (!__get_cpuid_count(0xD, 1, &a, &b, &c, &d) || !(a & (1u << 2))) return std::nullopt;  // XGETBV with ECX = 1
  uint32_t lo, hi;
  asm volatile("xgetbv" : "=a"(lo), "=d"(hi) : "c"(1));
  return uint64_t(lo) | uint64_t(hi) << 32;
}
constexpr uint64_t kUpperHalves = (1u << 2) | (1u << 6);

// Plain functions with the instruction in asm: one compiled for AVX would get
// a vzeroupper before its return from the compiler.
[[gnu::noinline]] void dirty_upper_halves() { asm volatile("vpcmpeqd %%ymm15, %%ymm15, %%ymm15" ::: "xmm15"); }
[[gnu::noinline]] void clear_upper_halves() { asm volatile("vzeroupper"); }

// The AVX builds of the pair test return with the vector registers' upper
// halves clear on every path. Left dirty, the caller's SSE code (the app's
// too) must merge them on Intel cores: the containment early out once left
// them so (GCC 12 emitted no vzeroupper on that way out), which made those
// pair tests about twice as slow.
TEST(Collide, AvxKernelsReturnWithTheUpperHalvesClear) {
  if (!vector_state_in_use() || !use_box_kernel(BoxKernel::avx2)) GTEST_SKIP() << "no AVX2 or no XGETBV with ECX = 1";
  ASSERT_TRUE(use_box_kernel(BoxKernel::best));
  // The reading is trusted only where it follows the state both ways.
  dirty_upper_halves();
  const bool seen_dirty = (*vector_state_in_use() & kUpperHalves) != 0;
  clear_upper_halves();
  const bool seen_clear = (*vector_state_in_use() & kUpperHalves) == 0;
  if (!seen_dirty || !seen_clear) GTEST_SKIP() << "XINUSE does not follow the upper halves here";

  // collide and collide_all, each entered with the upper halves dirty.
  const auto check = [](const PlacedTree& a, const PlacedTree& b, const std::string& what) {
    dirty_upper_halves();
    const PairTest r = collide(a, b);
    const uint64_t after_collide = *vector_state_in_use();
    std::vector<LeafPair> leaves;
    dirty_upper_halves();
    collide_all(a, b, leaves);
    const uint64_t after_collide_all = *vector_state_in_use();
    EXPECT_EQ(after_collide & kUpperHalves, 0u) << "collide, " << what;
    EXPECT_EQ(after_collide_all & kUpperHalves, 0u) << "collide_all, " << what;
    return r;
  };
  // A small tree inside one leaf of a large one: the containment early out
  // (the roots, A's 8 children, then one test for the whole small tree).
  // Then random pairs. Every AVX build the CPU runs.
  const ObjectTree large = full_tree(kCentred, 1), small = full_tree(kUnit, 3);
  const PlacedTree outer{&large, at({0, 0, 0}), 1};
  const PlacedTree inner{&small, at({0.3, 0.4, 0.2}, Eigen::Quaterniond::Identity(), 0.01), 3};
  for (const BoxKernel k : {BoxKernel::avx2, BoxKernel::avx512}) {
    if (!use_box_kernel(k)) continue;
    const std::string name = k == BoxKernel::avx2 ? "avx2" : "avx512";
    const PairTest early_out = check(outer, inner, name + ", small inside a leaf");
    EXPECT_TRUE(early_out.hit);
    EXPECT_EQ(early_out.box_tests, 10u) << name;
    std::mt19937 rng(23);
    for (int run = 0; run < 200; ++run) {
      const int depth_a = int(rng() % 4), depth_b = int(rng() % 4);
      const ObjectTree ta = random_tree(rng, depth_a), tb = random_tree(rng, depth_b);
      const double scale_b = std::pow(10.0, -2 + 2 * uniform01(rng));
      check({&ta, at({uniform01(rng) - 0.5, 0, 0}, random_rotation(rng)), depth_a},
            {&tb, at({0, uniform01(rng) - 0.5, 0}, random_rotation(rng), scale_b), depth_b},
            name + ", run " + std::to_string(run));
    }
  }
  ASSERT_TRUE(use_box_kernel(BoxKernel::best));
}
#endif

}  // namespace
}  // namespace octbake
