// WorldTree against a brute-force oracle: every overlapping AABB pair is a
// candidate (no miss), and the candidate set is exactly "shares a clamped cell
// or is in overflow (too many cells)", each pair once, sorted. Some boxes lie
// partly or wholly outside the world.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <tuple>
#include <utility>
#include <vector>

#include "octbake/world_tree.h"

namespace octbake {
namespace {

using Pairs = std::vector<std::pair<uint32_t, uint32_t>>;

// [0, 1) from 24 raw bits: the same on every standard library.
double unit(std::mt19937& rng) { return double(rng() >> 8) * (1.0 / 16777216.0); }
double uniform(std::mt19937& rng, double lo, double hi) { return lo + (hi - lo) * unit(rng); }

Aabb random_box(std::mt19937& rng, double reach, double max_half) {
  Eigen::Vector3d c, h;
  for (int k = 0; k < 3; ++k) c[k] = uniform(rng, -reach, reach);
  for (int k = 0; k < 3; ++k) h[k] = uniform(rng, 0.0, max_half);
  return {c - h, c + h};
}

// The oracle's own idea of the grid: cell = floor((x - min) / size), clamped.
struct GridOracle {
  Aabb world;
  int depth;
  int cell(double x, int k) const {
    const int n = 1 << depth;
    const double size = (world.max[k] - world.min[k]) / n;
    return std::clamp(int(std::floor((x - world.min[k]) / size)), 0, n - 1);
  }
  bool overflow(const Aabb& b) const {
    uint64_t count = 1;
    for (int k = 0; k < 3; ++k) count *= uint64_t(cell(b.max[k], k) - cell(b.min[k], k) + 1);
    return count > WorldTree::kMaxCells;
  }
  bool share_cell(const Aabb& a, const Aabb& b) const {
    for (int k = 0; k < 3; ++k)
      if (cell(a.max[k], k) < cell(b.min[k], k) || cell(b.max[k], k) < cell(a.min[k], k)) return false;
    return true;
  }
  std::array<int, 6> range(const Aabb& b) const {
    return {cell(b.min[0], 0), cell(b.min[1], 1), cell(b.min[2], 2), cell(b.max[0], 0), cell(b.max[1], 1), cell(b.max[2], 2)};
  }
};

// Checks `got` against the oracle over the present boxes; returns how many
// candidates truly overlap (the caller checks the test is not vacuous).
size_t check_pairs(const GridOracle& grid, const std::vector<Aabb>& boxes, const std::vector<bool>& present,
                   const Pairs& got) {
  for (size_t k = 0; k < got.size(); ++k) {
    EXPECT_LT(got[k].first, got[k].second);
    if (k > 0) {
      EXPECT_LT(got[k - 1], got[k]) << "not sorted or repeated at " << k;
    }
  }
  auto has = [&](uint32_t a, uint32_t b) { return std::binary_search(got.begin(), got.end(), std::pair(a, b)); };
  std::vector<bool> overflow(boxes.size());
  for (size_t i = 0; i < boxes.size(); ++i) overflow[i] = grid.overflow(boxes[i]);
  size_t expected = 0, overlapping = 0;
  for (uint32_t a = 0; a < boxes.size(); ++a) {
    if (!present[a]) continue;
    for (uint32_t b = a + 1; b < boxes.size(); ++b) {
      if (!present[b]) continue;
      const bool candidate = overflow[a] || overflow[b] || grid.share_cell(boxes[a], boxes[b]);
      if (overlaps(boxes[a], boxes[b])) {
        ++overlapping;
        EXPECT_TRUE(candidate) << "the oracle itself must not miss " << a << "," << b;
      }
      expected += candidate;
      if (candidate != has(a, b)) ADD_FAILURE() << (candidate ? "missed " : "spurious ") << a << "," << b;
    }
  }
  EXPECT_EQ(got.size(), expected);
  return overlapping;
}

class WorldTreeOracle : public ::testing::TestWithParam<int> {};

TEST_P(WorldTreeOracle, MatchesBruteForceThroughMovesAndRemovals) {
  const int depth = GetParam();
  const Aabb world{{-10, -10, -10}, {10, 10, 10}};
  const GridOracle grid{world, depth};
  WorldTree tree(world, depth);
  std::mt19937 rng(1234 + depth);

  // Reach 11 > 10: some boxes poke out or lie wholly outside the world.
  const uint32_t n = depth == 0 ? 200 : 400;  // depth 0: every pair is a candidate
  std::vector<Aabb> boxes(n);
  std::vector<bool> present(n, true);
  for (uint32_t i = 0; i < n; ++i) {
    boxes[i] = random_box(rng, 11.0, i % 50 == 0 ? 6.0 : 1.2);
    EXPECT_TRUE(tree.update(i, boxes[i])) << "a first insertion is a change";
  }
  EXPECT_EQ(tree.reinsertions(), 0u);
  Pairs pairs;
  tree.candidate_pairs(pairs);
  const size_t overlapping = check_pairs(grid, boxes, present, pairs);
  EXPECT_GT(overlapping, 40u) << "the scene must have overlaps for the test to mean anything";

  uint64_t changes = 0;
  // Moves of every size: within a cell, to neighbours, across the world
  // (cells emptied and refilled exercise the cell table's deletion).
  for (int round = 0; round < 10; ++round) {
    const double step = round % 3 == 0 ? 8.0 : round % 3 == 1 ? 1.5 : 0.2;
    for (uint32_t i = round % 3; i < n; i += 3) {
      const Eigen::Vector3d d(uniform(rng, -step, step), uniform(rng, -step, step), uniform(rng, -step, step));
      const Aabb moved{boxes[i].min + d, boxes[i].max + d};
      const bool expect_change = grid.range(moved) != grid.range(boxes[i]) || grid.overflow(moved) != grid.overflow(boxes[i]);
      EXPECT_EQ(tree.update(i, moved), expect_change) << "object " << i << " round " << round;
      changes += expect_change;
      boxes[i] = moved;
    }
    tree.candidate_pairs(pairs);
    check_pairs(grid, boxes, present, pairs);
  }
  EXPECT_EQ(tree.reinsertions(), changes);
  EXPECT_EQ(changes > 0, depth > 0);  // depth 0: one cell, nothing ever changes

  for (uint32_t i = 1; i < n; i += 4) {
    tree.remove(i);
    present[i] = false;
    EXPECT_FALSE(tree.contains(i));
  }
  tree.remove(1);  // twice: no-op
  tree.candidate_pairs(pairs);
  check_pairs(grid, boxes, present, pairs);

  // Re-adding a removed object is an insertion, not a reinsertion.
  const uint64_t before = tree.reinsertions();
  EXPECT_TRUE(tree.update(1, boxes[1]));
  present[1] = true;
  EXPECT_EQ(tree.reinsertions(), before);
  tree.candidate_pairs(pairs);
  check_pairs(grid, boxes, present, pairs);
}

// Depth 0: one cell (everything paired); 3: coarse; 6: boxes span many cells.
INSTANTIATE_TEST_SUITE_P(Depths, WorldTreeOracle, ::testing::Values(0, 3, 6));

// Runs the ranges in chunks of at most 7 items, last chunk first: a legal
// schedule no real executor would pick.
struct Backwards final : WorldTree::Parallel {
  int calls = 0;
  void for_ranges(size_t count, size_t grain, void (*task)(const void*, size_t, size_t), const void* ctx) override {
    ++calls;
    grain = std::clamp<size_t>(grain, 1, 7);
    for (size_t end = count; end > 0;) {
      const size_t begin = (end - 1) / grain * grain;
      task(ctx, begin, end);
      end = begin;
    }
  }
};

// What a caller can see of a tree: pairs, overflow, box queries and ray walks.
struct Seen {
  Pairs pairs;
  std::vector<uint32_t> overflow;
  std::vector<std::vector<uint32_t>> queries;
  std::vector<std::tuple<std::array<uint16_t, 3>, double, std::vector<uint32_t>>> walked;
  uint64_t reinsertions = 0;
  bool operator==(const Seen&) const = default;
};

Seen seen(const WorldTree& tree, uint32_t seed) {
  Seen s;
  tree.candidate_pairs(s.pairs);
  s.overflow = tree.overflow_ids();
  s.reinsertions = tree.reinsertions();
  std::mt19937 rng(seed);
  std::vector<uint32_t> got;
  for (int q = 0; q < 40; ++q) {
    tree.query_box(random_box(rng, 14.0, q % 8 == 0 ? 12.0 : 2.0), got);
    s.queries.push_back(got);
  }
  for (int r = 0; r < 20; ++r) {
    const Eigen::Vector3d o(uniform(rng, -20, 20), uniform(rng, -20, 20), uniform(rng, -20, 20));
    const Eigen::Vector3d d = Eigen::Vector3d(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)).normalized();
    WorldTree::RayWalk walk(tree, o, d, INFINITY);
    while (walk.next()) s.walked.emplace_back(walk.cell(), walk.entry(),
                                              std::vector<uint32_t>(walk.ids().begin(), walk.ids().end()));
  }
  return s;
}

class WorldTreeBatch : public ::testing::TestWithParam<int> {};

// The batch update_cells, in 1, 2 and 8 parts on a backwards schedule, against
// one-by-one updates and the brute-force oracle: new objects, objects going
// to and from overflow, objects over more cells than the batch's fast path,
// moves within a cell, to neighbours and across the world (cells emptied,
// refilled and dropped), removals and re-insertions between batches.
TEST_P(WorldTreeBatch, MatchesOneByOneUpdatesForEveryPartCount) {
  const int depth = GetParam();
  const Aabb world{{-10, -10, -10}, {10, 10, 10}};
  const GridOracle grid{world, depth};
  WorldTree one(world, depth);
  const std::array<size_t, 3> parts{1, 2, 8};
  std::vector<WorldTree> batched(parts.size(), WorldTree(world, depth));
  Backwards backwards;
  std::mt19937 rng(555 + depth);
  const uint32_t n = 300;
  std::vector<Aabb> boxes(n);
  std::vector<bool> present(n, false);
  // Mostly small boxes (2x2x2 cells or fewer at depth 6), a few large (more
  // cells than the fast path, or overflow).
  const auto new_box = [&](uint32_t i, const Aabb* from, double step) {
    const double half = i % 40 == 0 ? 6.0 : i % 13 == 0 ? 1.0 : 0.12;
    if (!from) return random_box(rng, 11.0, half);
    const Eigen::Vector3d d(uniform(rng, -step, step), uniform(rng, -step, step), uniform(rng, -step, step));
    Aabb b{from->min + d, from->max + d};
    if (i % 29 == 0 && step > 1) b = random_box(rng, 11.0, 6.0);  // to or from overflow
    return b;
  };
  size_t checked = 0;
  for (int round = 0; round < 14; ++round) {
    const double step = round % 3 == 0 ? 8.0 : round % 3 == 1 ? 0.4 : 0.05;
    std::vector<uint32_t> ids;
    for (uint32_t i = 0; i < n; ++i)
      if (round == 0 || !present[i] || rng() % 2 == 0) ids.push_back(i);
    std::shuffle(ids.begin(), ids.end(), rng);  // any order of distinct ids
    std::vector<WorldTree::CellRange> ranges;
    for (uint32_t i : ids) {
      boxes[i] = new_box(i, present[i] ? &boxes[i] : nullptr, step);
      present[i] = true;
      one.update(i, boxes[i]);
      ranges.push_back(one.cell_range(boxes[i]));
    }
    for (size_t t = 0; t < parts.size(); ++t) batched[t].update_cells(ids, ranges, backwards, parts[t]);
    // Removals between batches, re-inserted by a later one.
    if (round % 4 == 2)
      for (uint32_t i = round; i < n; i += 11) {
        one.remove(i);
        for (WorldTree& b : batched) b.remove(i);
        present[i] = false;
      }
    const Seen want = seen(one, round);
    check_pairs(grid, boxes, present, want.pairs);
    for (size_t t = 0; t < parts.size(); ++t) {
      ASSERT_EQ(seen(batched[t], round), want) << parts[t] << " parts, round " << round;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 14 * parts.size());
  EXPECT_GT(backwards.calls, 0);
  EXPECT_EQ(one.reinsertions() > 0, depth > 0);
}

INSTANTIATE_TEST_SUITE_P(Depths, WorldTreeBatch, ::testing::Values(0, 3, 6));

TEST(WorldTree, UpdateWithinSameCellsIsNotAChange) {
  WorldTree tree({{0, 0, 0}, {8, 8, 8}}, /*depth=*/3);  // unit cells
  ASSERT_TRUE(tree.update(7, {{2.2, 2.2, 2.2}, {2.4, 2.4, 2.4}}));
  EXPECT_FALSE(tree.update(7, {{2.3, 2.1, 2.6}, {2.9, 2.5, 2.7}}));
  EXPECT_EQ(tree.reinsertions(), 0u);
  EXPECT_TRUE(tree.update(7, {{2.3, 2.1, 2.6}, {3.1, 2.5, 2.7}}));  // now also in x cell 3
  EXPECT_EQ(tree.reinsertions(), 1u);
  EXPECT_FALSE(tree.in_overflow(7));
  EXPECT_TRUE(tree.update(7, {{-0.1, 2.1, 2.6}, {0.5, 2.5, 2.7}}));  // pokes out: clamped to cell 0
  EXPECT_FALSE(tree.in_overflow(7));
  EXPECT_EQ(tree.reinsertions(), 2u);
  EXPECT_FALSE(tree.update(7, {{-5, 2.1, 2.6}, {-4, 2.5, 2.7}}));  // wholly outside, same clamped cell
}

// needs_update(id, box) predicts update(id, box)'s answer: boxes walking in
// small steps (mostly within their cells) in and beyond a unit-cell world,
// jumping now and then, some huge (overflow), new, removed and unseen ids.
TEST(WorldTree, NeedsUpdatePredictsUpdate) {
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> step(-0.15, 0.15), at(-4, 36), unit(0, 1);
  WorldTree tree({{0, 0, 0}, {32, 32, 32}}, /*depth=*/5);
  std::vector<Aabb> boxes;
  int changes = 0, same = 0, overflow = 0;
  for (int k = 0; k < 6000; ++k) {
    const uint32_t id = uint32_t(k % 40);
    if (id >= boxes.size() || k % 53 == 0) {  // new or jumping
      const Eigen::Vector3d lo(at(rng), at(rng), at(rng));
      const double s = k % 7 == 0 ? 12 : 2 * unit(rng);  // 12^3 cells: over kMaxCells
      // Different extents per axis: an axis mixed up shows.
      const Aabb box{lo, lo + Eigen::Vector3d(s, s * (0.5 + unit(rng)), s * (0.5 + unit(rng)))};
      if (id >= boxes.size()) boxes.push_back(box); else boxes[id] = box;
    } else {
      const Eigen::Vector3d d(step(rng), step(rng), step(rng));
      boxes[id] = {boxes[id].min + d, boxes[id].max + d};
    }
    const Aabb& box = boxes[id];
    const bool predicted = tree.needs_update(id, box);
    ASSERT_EQ(predicted, tree.needs_update(id, tree.cell_range(box)));
    ASSERT_EQ(tree.update(id, box), predicted) << k;
    EXPECT_FALSE(tree.needs_update(id, box));
    (predicted ? changes : same)++;
    overflow += tree.in_overflow(id);
    if (k % 97 == 0) {  // gone: any box needs an update, as does an id never seen
      tree.remove(id);
      ASSERT_TRUE(tree.needs_update(id, box));
      ASSERT_TRUE(tree.update(id, box));
    }
    ASSERT_TRUE(tree.needs_update(1000 + id, box));
  }
  EXPECT_GT(changes, 500);  // both answers occur, and overflow
  EXPECT_GT(same, 500);
  EXPECT_GT(overflow, 0);
}

TEST(WorldTree, OutsideObjectsClampToBorderCells) {
  WorldTree tree({{0, 0, 0}, {8, 8, 8}}, /*depth=*/3);
  tree.update(0, {{1, 1, 1}, {1.5, 1.5, 1.5}});
  tree.update(1, {{6, 6, 6}, {6.5, 6.5, 6.5}});
  tree.update(2, {{20, 20, 20}, {21, 21, 21}});     // wholly outside: cell (7, 7, 7)
  tree.update(3, {{-1, 6, 6}, {6.2, 6.2, 6.2}});    // partly outside, x cells 0..6
  tree.update(4, {{8.5, 7.2, 7.2}, {9, 7.5, 7.5}});  // outside on x only: cell (7, 7, 7)
  Pairs pairs;
  tree.candidate_pairs(pairs);
  const Pairs expected{{1, 3}, {2, 4}};
  EXPECT_EQ(pairs, expected);
}

// A copy holds its own cells, whether their ids are kept in place (a few)
// or on the heap (many): moving every object in the original, or in the
// copy, leaves the other's pairs as they were.
TEST(WorldTree, CopiesAreIndependent) {
  WorldTree tree({{0, 0, 0}, {8, 8, 8}}, /*depth=*/3);
  std::vector<Aabb> boxes;
  for (int i = 0; i < 12; ++i) {  // 12 in cell (0, 0, 0): on the heap
    const double x = 0.05 * i;
    boxes.push_back({{x, 0.1, 0.1}, {x + 0.1, 0.2, 0.2}});
  }
  for (int i = 0; i < 3; ++i) boxes.push_back({{5.1, 5.1, 5.1 + 0.2 * i}, {5.2, 5.2, 5.2 + 0.2 * i}});  // in place
  for (uint32_t i = 0; i < boxes.size(); ++i) tree.update(i, boxes[i]);
  Pairs before;
  tree.candidate_pairs(before);
  ASSERT_EQ(before.size(), 12u * 11 / 2 + 3);
  WorldTree copy = tree;
  WorldTree assigned({{0, 0, 0}, {1, 1, 1}}, 0);
  assigned = copy;
  for (uint32_t i = 0; i < boxes.size(); ++i) tree.update(i, {boxes[i].min.array() + 3.0, boxes[i].max.array() + 3.0});
  Pairs got;
  copy.candidate_pairs(got);
  EXPECT_EQ(got, before);
  assigned.candidate_pairs(got);
  EXPECT_EQ(got, before);
  for (uint32_t i = 0; i < boxes.size(); ++i) copy.remove(i);
  assigned.candidate_pairs(got);
  EXPECT_EQ(got, before);
  tree.candidate_pairs(got);
  EXPECT_EQ(got.size(), before.size());  // moved together: the same pairs, other cells
  EXPECT_EQ(copy.cells_in_use(), 0u);
}

TEST(WorldTree, HugeObjectGoesToOverflowInsteadOfThousandsOfCells) {
  WorldTree tree({{0, 0, 0}, {64, 64, 64}}, /*depth=*/6);
  tree.update(0, {{0, 0, 0}, {64, 1, 64}});  // a ground plane: 64*2*64 cells
  EXPECT_TRUE(tree.in_overflow(0));
  tree.update(1, {{30, 30, 30}, {31, 31, 31}});
  EXPECT_FALSE(tree.in_overflow(1));
  Pairs pairs;
  tree.candidate_pairs(pairs);
  EXPECT_EQ(pairs, (Pairs{{0, 1}}));
}

// ---- queries ----

// A random world for the query tests: boxes in and around the world box, a
// few huge ones (overflow at depth >= 4).
struct QueryScene {
  Aabb world{{-10, -10, -10}, {10, 10, 10}};
  GridOracle grid;
  WorldTree tree;
  std::vector<Aabb> boxes;
  std::vector<bool> present;
  QueryScene(int depth, uint32_t n, std::mt19937& rng) : grid{world, depth}, tree(world, depth), boxes(n), present(n, true) {
    for (uint32_t i = 0; i < n; ++i) {
      boxes[i] = random_box(rng, 14.0, i % 97 == 0 ? 12.0 : 1.5);
      tree.update(i, boxes[i]);
    }
    for (uint32_t i = 3; i < n; i += 7) {
      tree.remove(i);
      present[i] = false;
    }
  }
  bool in_cell(uint32_t i, const std::array<int, 3>& c) const {
    const std::array<int, 6> r = grid.range(boxes[i]);
    for (int k = 0; k < 3; ++k)
      if (c[k] < r[k] || c[k] > r[3 + k]) return false;
    return true;
  }
};

class WorldTreeQuery : public ::testing::TestWithParam<int> {};

TEST_P(WorldTreeQuery, BoxQueryIsTheObjectsSharingACellPlusOverflow) {
  const int depth = GetParam();
  std::mt19937 rng(77 + depth);
  QueryScene s(depth, 600, rng);
  std::vector<uint32_t> got;
  size_t found = 0, overlapping = 0;
  for (int q = 0; q < 300; ++q) {
    // Small and large query boxes, some wholly outside the world.
    const Aabb box = random_box(rng, 16.0, q % 10 == 0 ? 15.0 : 2.0);
    s.tree.query_box(box, got);
    std::vector<uint32_t> want;
    for (uint32_t i = 0; i < s.boxes.size(); ++i) {
      if (!s.present[i]) continue;
      const bool candidate = s.grid.overflow(s.boxes[i]) || s.grid.share_cell(s.boxes[i], box);
      if (overlaps(s.boxes[i], box)) {
        ++overlapping;
        EXPECT_TRUE(candidate) << "the oracle itself must not miss " << i;
      }
      if (candidate) want.push_back(i);
    }
    ASSERT_EQ(got, want) << "query " << q;
    found += got.size();
  }
  EXPECT_GT(overlapping, 300u);
  EXPECT_GT(found, overlapping);
}

// Ray segment against a clamped cell's region (border cells reach to
// infinity): the entry distance, or -1 when missed.
double ray_cell(const GridOracle& g, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_max,
                const std::array<int, 3>& c, double inflate) {
  const int n = 1 << g.depth;
  double t0 = 0, t1 = t_max;
  for (int k = 0; k < 3; ++k) {
    const double size = (g.world.max[k] - g.world.min[k]) / n;
    const double lo = c[k] == 0 ? -INFINITY : g.world.min[k] + c[k] * size - inflate;
    const double hi = c[k] == n - 1 ? INFINITY : g.world.min[k] + (c[k] + 1) * size + inflate;
    if (d[k] == 0) {
      if (o[k] < lo || o[k] > hi) return -1;
      continue;
    }
    double ta = (lo - o[k]) / d[k], tb = (hi - o[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta), t1 = std::min(t1, tb);
    if (t0 > t1) return -1;
  }
  return t0;
}

TEST_P(WorldTreeQuery, RayWalkVisitsEveryOccupiedCellTheRayMeetsInOrder) {
  const int depth = GetParam();
  std::mt19937 rng(91 + depth);
  QueryScene s(depth, 400, rng);
  // The occupied cells (by the oracle), with their occupants.
  std::vector<std::pair<std::array<int, 3>, std::vector<uint32_t>>> occupied;
  {
    std::vector<std::array<int, 3>> all;
    for (uint32_t i = 0; i < s.boxes.size(); ++i) {
      if (!s.present[i] || s.grid.overflow(s.boxes[i])) continue;
      const std::array<int, 6> r = s.grid.range(s.boxes[i]);
      for (int z = r[2]; z <= r[5]; ++z)
        for (int y = r[1]; y <= r[4]; ++y)
          for (int x = r[0]; x <= r[3]; ++x) all.push_back({x, y, z});
    }
    std::sort(all.begin(), all.end());
    all.erase(std::unique(all.begin(), all.end()), all.end());
    for (const auto& c : all) {
      std::vector<uint32_t> ids;
      for (uint32_t i = 0; i < s.boxes.size(); ++i)
        if (s.present[i] && !s.grid.overflow(s.boxes[i]) && s.in_cell(i, c)) ids.push_back(i);
      occupied.push_back({c, ids});
    }
  }
  size_t met = 0, outside_met = 0;
  for (int r = 0; r < 300; ++r) {
    // Origins in and far around the world box; some directions axis-aligned
    // or with a zero component; finite and infinite segments.
    const Eigen::Vector3d o(uniform(rng, -40, 40), uniform(rng, -40, 40), uniform(rng, -40, 40));
    Eigen::Vector3d d(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
    if (r % 5 == 0) d[r % 3] = 0;
    if (r % 7 == 0) d = Eigen::Vector3d::Unit(r % 3) * (r % 2 ? 1 : -1);
    d.normalize();
    const double t_max = r % 3 == 0 ? INFINITY : uniform(rng, 0, 60);
    const bool outside = (o.cwiseAbs().array() > 10).any();
    std::vector<std::array<int, 3>> walked;
    double last = 0;
    WorldTree::RayWalk walk(s.tree, o, d, t_max);
    while (walk.next()) {
      const std::array<int, 3> c{walk.cell()[0], walk.cell()[1], walk.cell()[2]};
      EXPECT_GE(walk.entry(), last) << "entries in order";
      last = walk.entry();
      auto it = std::find_if(occupied.begin(), occupied.end(), [&](const auto& e) { return e.first == c; });
      ASSERT_NE(it, occupied.end()) << "walked an empty cell";
      EXPECT_EQ(std::vector<uint32_t>(walk.ids().begin(), walk.ids().end()), it->second);
      // Met by the ray (up to the tube's width), and entered no earlier than walked.
      EXPECT_GE(ray_cell(s.grid, o, d, t_max, c, 1e-6), 0.0) << "walked a cell the ray does not meet, ray " << r;
      const double t = ray_cell(s.grid, o, d, t_max, c, 0);
      if (t >= 0) {
        EXPECT_LE(walk.entry(), t + 1e-9);
      }
      walked.push_back(c);
    }
    std::vector<std::array<int, 3>> sorted = walked;
    std::sort(sorted.begin(), sorted.end());
    EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end()) << "a cell walked twice";
    for (const auto& [c, ids] : occupied) {
      const double t = ray_cell(s.grid, o, d, t_max, c, 0);
      if (t < 0) continue;
      ++met, outside_met += outside;
      EXPECT_TRUE(std::binary_search(sorted.begin(), sorted.end(), c))
          << "missed cell " << c[0] << "," << c[1] << "," << c[2] << " at " << t << ", ray " << r;
    }
  }
  EXPECT_GE(met, 300u);
  EXPECT_GT(outside_met, 100u);  // rays from outside the world box reach occupied cells
}

// A ray wholly outside the world box still walks the border cells, which
// hold the objects clamped into them.
TEST(WorldTree, RayOutsideTheWorldWalksTheBorderCells) {
  WorldTree tree({{0, 0, 0}, {8, 8, 8}}, /*depth=*/3);
  tree.update(0, {{20, 3.5, 20}, {21, 3.6, 21}});  // clamped to x = 7, z = 7
  tree.update(1, {{4, 4, 4}, {4.5, 4.5, 4.5}});
  std::vector<std::array<uint16_t, 3>> cells;
  // Along y, far outside on x and z: only the border column (7, y, 7).
  WorldTree::RayWalk walk(tree, {30, -50, 30}, {0, 1, 0}, INFINITY);
  while (walk.next()) cells.push_back(walk.cell());
  ASSERT_EQ(cells.size(), 1u);
  EXPECT_EQ(cells[0], (std::array<uint16_t, 3>{7, 3, 7}));
  // y = 3 is entered at y = 3 (cell boundary), 53 along the ray (up to the tube).
  WorldTree::RayWalk again(tree, {30, -50, 30}, {0, 1, 0}, INFINITY);
  ASSERT_TRUE(again.next());
  EXPECT_NEAR(again.entry(), 53.0, 1e-6);
  EXPECT_EQ(std::vector<uint32_t>(again.ids().begin(), again.ids().end()), std::vector<uint32_t>{0});
  // Stopped short of it: nothing.
  WorldTree::RayWalk shorter(tree, {30, -50, 30}, {0, 1, 0}, 52.0);
  EXPECT_FALSE(shorter.next());
  // An empty tree walks nothing.
  WorldTree empty({{0, 0, 0}, {8, 8, 8}}, 3);
  WorldTree::RayWalk none(empty, {1, 1, 1}, {1, 0, 0}, INFINITY);
  EXPECT_FALSE(none.next());
  std::vector<uint32_t> ids{5};
  empty.query_box({{0, 0, 0}, {8, 8, 8}}, ids);
  EXPECT_TRUE(ids.empty());
}

INSTANTIATE_TEST_SUITE_P(Depths, WorldTreeQuery, ::testing::Values(0, 2, 4, 6));

}  // namespace
}  // namespace octbake
