// WorldTree with objects whose sizes differ 400x and more (up to 100000x),
// against brute force: candidate pairs are exactly "share a (clamped) cell,
// or overflow", overlapping pairs exactly the overlapping boxes (also in scan
// parts run backwards), box queries and ray walks miss nothing; objects grow
// and shrink 4x a step (from one cell to thousands, to and from overflow), in
// one-by-one and batch updates (which must agree), in a world near the origin
// and one 1e6 away.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <random>
#include <utility>
#include <vector>

#include "octbake/world_tree.h"

namespace octbake {
namespace {

using Pairs = std::vector<std::pair<uint32_t, uint32_t>>;

double unit(std::mt19937& rng) { return double(rng() >> 8) * (1.0 / 16777216.0); }
double uniform(std::mt19937& rng, double lo, double hi) { return lo + (hi - lo) * unit(rng); }

struct Oracle {
  Aabb world;
  int depth;
  int cell(double x, int k) const {
    const int n = 1 << depth;
    const double t = (x - world.min[k]) * (n / (world.max[k] - world.min[k]));
    return t >= n ? n - 1 : t > 0 ? int(t) : 0;
  }
  uint64_t cells(const Aabb& b) const {
    uint64_t count = 1;
    for (int k = 0; k < 3; ++k) count *= uint64_t(cell(b.max[k], k) - cell(b.min[k], k) + 1);
    return count;
  }
  bool overflow(const Aabb& b) const { return cells(b) > WorldTree::kMaxCells; }
  bool share_cell(const Aabb& a, const Aabb& b) const {
    for (int k = 0; k < 3; ++k)
      if (cell(a.max[k], k) < cell(b.min[k], k) || cell(b.max[k], k) < cell(a.min[k], k)) return false;
    return true;
  }
  bool same_cells(const Aabb& a, const Aabb& b) const {
    for (int k = 0; k < 3; ++k)
      if (cell(a.min[k], k) != cell(b.min[k], k) || cell(a.max[k], k) != cell(b.max[k], k)) return false;
    return true;
  }
};

// Sizes log-uniform over [1e-5, 1] of the world's width: a spread of 100000x.
Aabb random_box(std::mt19937& rng, const Aabb& world) {
  const Eigen::Vector3d size = world.max - world.min, mid = 0.5 * (world.min + world.max);
  const double half = 0.5 * size.maxCoeff() * std::pow(10.0, uniform(rng, -5, 0));
  Eigen::Vector3d c, h;
  for (int k = 0; k < 3; ++k) c[k] = mid[k] + size[k] * uniform(rng, -0.55, 0.55);  // some poke out
  for (int k = 0; k < 3; ++k) h[k] = half * uniform(rng, 0.2, 1.0);
  return {c - h, c + h};
}

// The box grown or shrunk about its centre by `f`, and moved by `d`.
Aabb reshaped(const Aabb& b, double f, const Eigen::Vector3d& d) {
  const Eigen::Vector3d c = 0.5 * (b.min + b.max) + d, h = 0.5 * f * (b.max - b.min);
  return {c - h, c + h};
}

struct Collect final : WorldTree::PairSink {
  std::mutex mutex;
  Pairs pairs;
  void take(std::span<const std::pair<uint32_t, uint32_t>> p) override {
    std::lock_guard lock(mutex);
    pairs.insert(pairs.end(), p.begin(), p.end());
  }
};

// The ray's entry into the closed box, or -1.
double ray_box(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_max, const Aabb& b) {
  double t0 = 0, t1 = t_max;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0) {
      if (o[k] < b.min[k] || o[k] > b.max[k]) return -1;
      continue;
    }
    double ta = (b.min[k] - o[k]) / d[k], tb = (b.max[k] - o[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta), t1 = std::min(t1, tb);
    if (t0 > t1) return -1;
  }
  return t0;
}

// overlapping_pairs, and the scan in parts (last first), give `want`.
void expect_overlapping_pairs(const WorldTree& tree, const std::vector<Aabb>& boxes, const Pairs& want) {
  Pairs got;
  tree.overlapping_pairs(boxes, got);
  EXPECT_EQ(got, want);
  Collect sink;
  for (size_t p = tree.scan_parts(); p-- > 0;) tree.scan_part(p, boxes, sink);
  tree.finish_pairs(boxes, sink.pairs);
  EXPECT_EQ(sink.pairs, want);
}

// Everything a caller sees, checked against brute force; returns the number
// of overlapping pairs (the caller checks the scene is not vacuous).
size_t check(const Oracle& g, const WorldTree& tree, const std::vector<Aabb>& boxes, const std::vector<bool>& present,
             std::mt19937& rng) {
  const uint32_t n = uint32_t(boxes.size());
  Pairs want_candidates, want_overlaps;
  for (uint32_t a = 0; a < n; ++a)
    for (uint32_t b = a + 1; b < n; ++b) {
      if (!present[a] || !present[b]) continue;
      if (g.overflow(boxes[a]) || g.overflow(boxes[b]) || g.share_cell(boxes[a], boxes[b]))
        want_candidates.emplace_back(a, b);
      if (overlaps(boxes[a], boxes[b])) want_overlaps.emplace_back(a, b);
    }
  Pairs got;
  tree.candidate_pairs(got);
  EXPECT_EQ(got, want_candidates);
  expect_overlapping_pairs(tree, boxes, want_overlaps);

  std::vector<uint32_t> found;
  for (int q = 0; q < 20; ++q) {
    const Aabb box = random_box(rng, g.world);
    tree.query_box(box, found);
    std::vector<uint32_t> want;
    for (uint32_t i = 0; i < n; ++i)
      if (present[i] && (g.overflow(boxes[i]) || g.share_cell(boxes[i], box))) want.push_back(i);
    EXPECT_EQ(found, want) << "query " << q;
  }

  // Rays: every box the ray meets is an overflow object or in a cell walked
  // no later than the ray enters the box.
  const Eigen::Vector3d size = g.world.max - g.world.min;
  for (int r = 0; r < 20; ++r) {
    Eigen::Vector3d o, d(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
    for (int k = 0; k < 3; ++k) o[k] = g.world.min[k] + size[k] * uniform(rng, -0.2, 1.2);
    if (r % 4 == 0) d[r % 3] = 0;
    d.normalize();
    std::vector<double> first(n, INFINITY);
    double last = 0;
    WorldTree::RayWalk walk(tree, o, d, INFINITY);
    while (walk.next()) {
      EXPECT_GE(walk.entry(), last);
      last = walk.entry();
      for (uint32_t i : walk.ids()) first[i] = std::min(first[i], walk.entry());
    }
    for (uint32_t i : tree.overflow_ids()) first[i] = 0;
    for (uint32_t i = 0; i < n; ++i) {
      if (!present[i]) continue;
      const double t = ray_box(o, d, INFINITY, boxes[i]);
      if (t < 0) continue;
      EXPECT_LE(first[i], t + 1e-9 * (1 + t)) << "ray " << r << " object " << i;
    }
  }
  return want_overlaps.size();
}

// Runs the ranges in chunks of at most 5 items, last chunk first.
struct Backwards final : WorldTree::Parallel {
  void for_ranges(size_t count, size_t grain, void (*task)(const void*, size_t, size_t), const void* ctx) override {
    grain = std::clamp<size_t>(grain, 1, 5);
    for (size_t end = count; end > 0;) {
      const size_t begin = (end - 1) / grain * grain;
      task(ctx, begin, end);
      end = begin;
    }
  }
};

class WorldTreeSizes : public ::testing::TestWithParam<std::tuple<int, double>> {};

TEST_P(WorldTreeSizes, MixedSizesGrowingAndShrinkingMatchBruteForce) {
  const auto [depth, offset] = GetParam();
  const Eigen::Vector3d at = Eigen::Vector3d::Constant(offset);
  const Aabb world{at + Eigen::Vector3d(-100, -60, -80), at + Eigen::Vector3d(100, 60, 80)};
  const Oracle g{world, depth};
  WorldTree one(world, depth);
  std::vector<WorldTree> batched(3, WorldTree(world, depth));
  const std::array<size_t, 3> parts{1, 2, 8};
  Backwards backwards;
  std::mt19937 rng(4242 + depth);
  const uint32_t n = 260;
  std::vector<Aabb> boxes(n);
  std::vector<bool> present(n, false);
  uint64_t changes = 0;
  size_t overlapping = 0, one_cell = 0, many_cells = 0;
  for (int round = 0; round < 12; ++round) {
    std::vector<uint32_t> ids;
    for (uint32_t i = 0; i < n; ++i) {
      if (round > 0 && present[i] && rng() % 3 == 0) continue;  // stays
      Aabb b;
      if (!present[i]) {
        b = random_box(rng, world);
      } else {
        // Grow or shrink up to 4x, move by up to a tenth of its size or a little.
        const double f = std::pow(4.0, uniform(rng, -1, 1));
        const double step = std::max(0.1 * (boxes[i].max - boxes[i].min).maxCoeff(), 0.5);
        b = reshaped(boxes[i], f, Eigen::Vector3d(uniform(rng, -step, step), uniform(rng, -step, step),
                                                   uniform(rng, -step, step)));
      }
      const bool change = !present[i] || !g.same_cells(b, boxes[i]) || g.overflow(b) != g.overflow(boxes[i]);
      EXPECT_EQ(one.update(i, b), change);
      changes += present[i] && change;
      boxes[i] = b;
      present[i] = true;
      ids.push_back(i);
    }
    std::shuffle(ids.begin(), ids.end(), rng);  // the batch takes any order
    std::vector<WorldTree::CellRange> shuffled;
    for (uint32_t i : ids) shuffled.push_back(one.cell_range(boxes[i]));
    for (size_t t = 0; t < parts.size(); ++t) batched[t].update_cells(ids, shuffled, backwards, parts[t]);
    if (round % 3 == 2)
      for (uint32_t i = round; i < n; i += 9) {
        one.remove(i);
        for (WorldTree& b : batched) b.remove(i);
        present[i] = false;
      }
    // The table holds exactly the occupied cells: none left empty piles up.
    std::vector<uint64_t> occupied;
    for (uint32_t i = 0; i < n; ++i) {
      if (!present[i] || g.overflow(boxes[i])) continue;
      for (int z = g.cell(boxes[i].min[2], 2); z <= g.cell(boxes[i].max[2], 2); ++z)
        for (int y = g.cell(boxes[i].min[1], 1); y <= g.cell(boxes[i].max[1], 1); ++y)
          for (int x = g.cell(boxes[i].min[0], 0); x <= g.cell(boxes[i].max[0], 0); ++x)
            occupied.push_back((uint64_t(z) << 40) | (uint64_t(y) << 20) | uint64_t(x));
    }
    std::sort(occupied.begin(), occupied.end());
    const size_t cells = size_t(std::unique(occupied.begin(), occupied.end()) - occupied.begin());
    EXPECT_EQ(one.cells_in_use(), cells) << "round " << round;
    for (const WorldTree& b : batched) EXPECT_EQ(b.cells_in_use(), cells) << "round " << round;
    std::mt19937 r1(round);
    overlapping += check(g, one, boxes, present, r1);
    for (size_t t = 0; t < parts.size(); ++t) {
      std::mt19937 r3(round);
      check(g, batched[t], boxes, present, r3);
      Pairs a, b;
      one.candidate_pairs(a);
      batched[t].candidate_pairs(b);
      EXPECT_EQ(a, b);
      EXPECT_EQ(batched[t].reinsertions(), one.reinsertions());
      EXPECT_EQ(batched[t].overflow_ids(), one.overflow_ids());
    }
    for (uint32_t i = 0; i < n; ++i)
      if (present[i]) one_cell += g.cells(boxes[i]) == 1, many_cells += g.cells(boxes[i]) > 8;
  }
  EXPECT_EQ(one.reinsertions(), changes);
  EXPECT_GT(overlapping, 500u);
  // Not vacuous: objects in one cell and objects over many (a grid of 8
  // cells or fewer has no "many").
  EXPECT_GT(one_cell, 100u);
  if (depth >= 3) {
    EXPECT_GT(many_cells, 100u);
  }
}

// Depth 0: one cell of 260 (swept); 1: eight crowded cells; 3: coarse; 6;
// 10: the deepest (most big boxes in overflow); at the origin and 1e6 away.
INSTANTIATE_TEST_SUITE_P(DepthsAndOffsets, WorldTreeSizes,
                         ::testing::Combine(::testing::Values(0, 1, 3, 6, 10), ::testing::Values(0.0, 1e6)));

// A crowded cell is swept by box min x: touching boxes (closed intervals),
// equal min x, boxes of zero width and one spanning the cell give exactly the
// overlapping pairs, in every scan.
TEST(WorldTreeSizes, CrowdedCellOfTouchingBoxesMatchesBruteForce) {
  const Aabb world{{0, 0, 0}, {16, 16, 16}};
  WorldTree tree(world, /*depth=*/1);  // cells of 8
  std::vector<Aabb> boxes;
  for (int x = 0; x < 6; ++x)  // a 6 x 6 x 2 lattice of unit boxes, faces touching
    for (int y = 0; y < 6; ++y)
      for (int z = 0; z < 2; ++z) boxes.push_back({Eigen::Vector3d(x, y, z), Eigen::Vector3d(x + 1, y + 1, z + 1)});
  for (int k = 0; k < 6; ++k)  // flat and point boxes on the lattice lines
    boxes.push_back({Eigen::Vector3d(k, 2, 0.5), Eigen::Vector3d(k, 3, 0.5 * (k % 2) + 0.5)});
  boxes.push_back({Eigen::Vector3d(0.5, 0.5, 0.5), Eigen::Vector3d(7.5, 7.5, 7.5)});  // over all of them
  for (uint32_t i = 0; i < boxes.size(); ++i) tree.update(i, boxes[i]);
  Pairs want;
  for (uint32_t a = 0; a < boxes.size(); ++a)
    for (uint32_t b = a + 1; b < boxes.size(); ++b)
      if (overlaps(boxes[a], boxes[b])) want.emplace_back(a, b);
  expect_overlapping_pairs(tree, boxes, want);
  EXPECT_GT(want.size(), 72u * 6);  // each lattice box touches its up to 26 neighbours
}

// The pair scan fetches cells, ids and boxes ahead only in a world too big
// to stay in a core's caches (past 128 KB of them): 40 objects and 4000
// (~220 KB of ids and boxes alone), both with crowded cells and a few objects
// over many cells, give brute force's pairs through moves either way.
TEST(WorldTreeSizes, ScanOfSmallAndLargeWorldsMatchesBruteForce) {
  for (const uint32_t n : {40u, 4000u}) {
    const Aabb world{{-50, -50, -50}, {50, 50, 50}};
    WorldTree tree(world, /*depth=*/5);  // cells of 3.125
    std::mt19937 rng(77 + n);
    const double reach = n == 40 ? 8 : 50;  // the small world crowded too
    std::vector<Aabb> boxes(n);
    for (uint32_t i = 0; i < n; ++i) {
      const double half = i % 97 == 0 ? 12 : uniform(rng, 0.2, 3);
      const Eigen::Vector3d c(uniform(rng, -reach, reach), uniform(rng, -reach, reach), uniform(rng, -reach, reach));
      boxes[i] = {c.array() - half, c.array() + half};
      tree.update(i, boxes[i]);
    }
    for (int round = 0; round < 3; ++round) {
      Pairs want;
      for (uint32_t a = 0; a < n; ++a)
        for (uint32_t b = a + 1; b < n; ++b)
          if (overlaps(boxes[a], boxes[b])) want.emplace_back(a, b);
      expect_overlapping_pairs(tree, boxes, want);
      EXPECT_GT(want.size(), size_t(n)) << n << " objects: the scene must have overlaps to mean anything";
      for (uint32_t i = uint32_t(round); i < n; i += 2) {  // half of them move, many to other cells
        const Eigen::Vector3d d(uniform(rng, -2, 2), uniform(rng, -2, 2), uniform(rng, -2, 2));
        boxes[i] = {boxes[i].min + d, boxes[i].max + d};
        tree.update(i, boxes[i]);
      }
    }
  }
}

// A batch that makes many cells (a load) leaves room for twice the cells in
// use, so the frames after it, each making a few new cells, grow neither the
// cell array nor the table (a growth copies or rehashes every cell: after
// loading 20k objects it made the first moving frame 16 ms against 3 ms).
// The pairs stay brute force's throughout.
TEST(WorldTreeSizes, LoadLeavesRoomForTheFramesAfterIt) {
  const Aabb world{{-50, -50, -50}, {50, 50, 50}};
  WorldTree tree(world, /*depth=*/6);  // cells of 1.5625
  std::mt19937 rng(31);
  const uint32_t n = 3000;
  std::vector<Aabb> boxes(n);
  std::vector<uint32_t> ids(n);
  std::vector<WorldTree::CellRange> ranges(n);
  for (uint32_t i = 0; i < n; ++i) {
    const Eigen::Vector3d c(uniform(rng, -48, 48), uniform(rng, -48, 48), uniform(rng, -48, 48));
    const double half = i % 50 == 0 ? 4 : uniform(rng, 0.1, 1.5);
    boxes[i] = {c.array() - half, c.array() + half};
    ids[i] = i;
    ranges[i] = tree.cell_range(boxes[i]);
  }
  Backwards backwards;
  tree.update_cells(ids, ranges, backwards, 2);
  const size_t loaded = tree.cells_in_use(), room = tree.cell_room();
  EXPECT_GE(room, 2 * loaded);
  size_t made = 0;
  for (int frame = 0; frame < 6; ++frame) {
    std::vector<uint32_t> moved;
    std::vector<WorldTree::CellRange> moved_ranges;
    for (uint32_t i = uint32_t(frame); i < n; i += 20) {  // 5% of them, about a cell each
      const Eigen::Vector3d d(uniform(rng, -1.5, 1.5), uniform(rng, -1.5, 1.5), uniform(rng, -1.5, 1.5));
      boxes[i] = {boxes[i].min + d, boxes[i].max + d};
      moved.push_back(i);
      moved_ranges.push_back(tree.cell_range(boxes[i]));
    }
    const size_t before = tree.cells_in_use();
    tree.update_cells(moved, moved_ranges, backwards, 2);
    made += tree.cells_in_use() > before ? tree.cells_in_use() - before : 0;
    EXPECT_EQ(tree.cell_room(), room) << "frame " << frame;
    Pairs want;
    for (uint32_t a = 0; a < n; ++a)
      for (uint32_t b = a + 1; b < n; ++b)
        if (overlaps(boxes[a], boxes[b])) want.emplace_back(a, b);
    expect_overlapping_pairs(tree, boxes, want);
  }
  EXPECT_GT(made, 0u) << "the frames must make new cells for the test to mean anything";
}

// Hundreds of objects too big for the cells (overflow), a few of them too
// big even for the coarse cells, among small ones, some poking out of the
// world: the box-filtered pairs (which then go through coarse cells) are
// exactly the overlapping ones, through moves, at the origin and at 1e6.
TEST(WorldTreeSizes, ManyOverflowObjectsMatchBruteForce) {
  for (double offset : {0.0, 1e6}) {
    const Eigen::Vector3d at = Eigen::Vector3d::Constant(offset);
    const Aabb world{at, at + Eigen::Vector3d::Constant(256)};
    WorldTree tree(world, /*depth=*/8);  // cells of 1, coarse cells of 8
    std::mt19937 rng(77);
    const auto box = [&](double lo, double hi, double spill) {
      const Eigen::Vector3d h(uniform(rng, lo, hi), uniform(rng, lo, hi), uniform(rng, lo, hi));
      const Eigen::Vector3d c(uniform(rng, -spill, 256 + spill), uniform(rng, -spill, 256 + spill),
                              uniform(rng, -spill, 256 + spill));
      return Aabb{at + c - h, at + c + h};
    };
    std::vector<Aabb> boxes;
    for (int i = 0; i < 1000; ++i) boxes.push_back(box(0.1, 2, 4));  // in cells
    for (int i = 0; i < 500; ++i) boxes.push_back(box(6, 20, 10));  // overflow: 12^3 cells and more
    for (int i = 0; i < 4; ++i) boxes.push_back(box(90, 140, 0));  // over more than 4096 coarse cells
    ASSERT_GT(uint64_t(500) * boxes.size(), WorldTree::kCoarseFrom);
    for (int round = 0; round < 3; ++round) {
      if (round > 0)
        for (size_t i = round; i < boxes.size(); i += 3) {
          const Eigen::Vector3d d(uniform(rng, -3, 3), uniform(rng, -3, 3), uniform(rng, -3, 3));
          boxes[i] = {boxes[i].min + d, boxes[i].max + d};
        }
      for (uint32_t i = 0; i < boxes.size(); ++i) tree.update(i, boxes[i]);
      EXPECT_GE(tree.overflow_ids().size(), 480u);
      Pairs want;
      for (uint32_t a = 0; a < boxes.size(); ++a)
        for (uint32_t b = a + 1; b < boxes.size(); ++b)
          if (overlaps(boxes[a], boxes[b])) want.emplace_back(a, b);
      expect_overlapping_pairs(tree, boxes, want);
      EXPECT_GT(want.size(), 2000u) << "offset " << offset << " round " << round;
    }
  }
}

// Overflow objects whose coarse cells would cost more than pairing them with
// every object: a hundred huge ones (too many coarse cells in all), and 600
// in one spot (too many of them per coarse cell, found only once their index
// is sorted). Either way all their pairs come from pairing with everything,
// also for the few beyond kCoarseMaxCells: exactly the overlapping boxes.
TEST(WorldTreeSizes, OverflowObjectsLeftToPairWithAllMatchBruteForce) {
  for (int shape : {0, 1}) {
    const Aabb world{{0, 0, 0}, {256, 256, 256}};
    WorldTree tree(world, /*depth=*/8);
    std::mt19937 rng(5 + shape);
    std::vector<Aabb> boxes;
    const auto add = [&](int n, double lo, double hi, double from, double to) {
      for (int i = 0; i < n; ++i) {
        const Eigen::Vector3d h(uniform(rng, lo, hi), uniform(rng, lo, hi), uniform(rng, lo, hi));
        const Eigen::Vector3d c(uniform(rng, from, to), uniform(rng, from, to), uniform(rng, from, to));
        boxes.push_back({c - h, c + h});
      }
    };
    add(shape == 0 ? 3000 : 1500, 0.1, 2, -4, 260);  // in cells
    if (shape == 0) add(100, 50, 60, 0, 256);        // ~3,000 coarse cells each
    if (shape == 1) add(600, 14, 14, 120, 136);      // ~100 coarse cells each, all in ~200
    add(2, 100, 120, 0, 256);                        // over kCoarseMaxCells
    const size_t overflow = boxes.size() - (shape == 0 ? 3000 : 1500);
    ASSERT_GT(uint64_t(overflow) * boxes.size(), WorldTree::kCoarseFrom);
    for (uint32_t i = 0; i < boxes.size(); ++i) tree.update(i, boxes[i]);
    EXPECT_EQ(tree.overflow_ids().size(), overflow);
    Pairs want;
    for (uint32_t a = 0; a < boxes.size(); ++a)
      for (uint32_t b = a + 1; b < boxes.size(); ++b)
        if (overlaps(boxes[a], boxes[b])) want.emplace_back(a, b);
    expect_overlapping_pairs(tree, boxes, want);
    EXPECT_GT(want.size(), shape == 0 ? 4000u : 100000u) << "shape " << shape;
  }
}

// A needle grows from a speck to the world's width and back (256 x 2 x 2
// cells at most: never overflow): its pairs with a few fixed small objects
// are exactly the overlapping ones at every step, and a ray along it finds it.
TEST(WorldTreeSizes, GrowingNeedleKeepsItsPairs) {
  const Aabb world{{0, 0, 0}, {1024, 1024, 1024}};
  WorldTree tree(world, /*depth=*/8);  // cells of 4
  std::vector<Aabb> boxes;
  for (int i = 0; i < 12; ++i) {
    const Eigen::Vector3d c(292 + 40 * i, 511.8 + 0.2 * (i % 3), 512 + 0.2 * (i % 2));  // along the needle
    boxes.push_back({c.array() - 0.3, c.array() + 0.3});
    tree.update(uint32_t(i), boxes.back());
  }
  const Eigen::Vector3d centre(512, 512, 512);
  boxes.push_back({});
  for (int step = 0; step <= 40; ++step) {
    const double half = 0.01 * std::pow(2.0, (step <= 20 ? step : 40 - step) * 0.8);  // 0.01 .. ~660
    const Eigen::Vector3d h(half, 0.3, 0.3);
    boxes.back() = {centre - h, centre + h};
    tree.update(12, boxes.back());
    Pairs got, want;
    tree.overlapping_pairs(boxes, got);
    for (uint32_t a = 0; a < boxes.size(); ++a)
      for (uint32_t b = a + 1; b < boxes.size(); ++b)
        if (overlaps(boxes[a], boxes[b])) want.emplace_back(a, b);
    EXPECT_EQ(got, want) << "step " << step;
    WorldTree::RayWalk walk(tree, {0, 512.5, 512.5}, {1, 0, 0}, INFINITY);
    bool found = false;
    while (walk.next()) found |= std::binary_search(walk.ids().begin(), walk.ids().end(), 12u);
    EXPECT_FALSE(tree.in_overflow(12));
    EXPECT_TRUE(found) << "step " << step;
  }
}

}  // namespace
}  // namespace octbake
