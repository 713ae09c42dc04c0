// build_tree on several threads: the same masks for every thread budget,
// equal to a brute-force level-by-level build; the budget is respected and
// given back; progress is reported as documented.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numbers>
#include <random>
#include <set>
#include <thread>
#include <vector>

#include "build_tree.h"
#include "occupancy.h"
#include "random_soup.h"
#include "seeded_random.h"

namespace octbake {
namespace {

using V = Eigen::Vector3d;
using test::random_point;

#if defined(__SANITIZE_ADDRESS__)
constexpr int kScale = 4;  // sanitizers: smaller meshes and fewer rounds, same code paths
const std::vector<int> kDepths = {1, 3, 6}, kHelpers = {1, 7};
#else
constexpr int kScale = 1;
const std::vector<int> kDepths = {1, 2, 3, 4, 6}, kHelpers = {0, 1, 2, 7};
#endif

using test::random_soup;

// A closed UV sphere of radius 1 centred at `c`: 2 * segments * (rings - 1) triangles.
void add_sphere(Mesh& m, const V& c, int rings, int segments) {
  const uint32_t base = uint32_t(m.positions.size());
  m.positions.push_back(c + V(0, 0, 1));
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const double th = std::numbers::pi * r / rings, ph = 2 * std::numbers::pi * s / segments;
      m.positions.push_back(c + V(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
    }
  m.positions.push_back(c + V(0, 0, -1));
  auto at = [&](int r, int s) { return base + 1 + uint32_t((r - 1) * segments + s % segments); };
  const uint32_t south = uint32_t(m.positions.size() - 1);
  for (int s = 0; s < segments; ++s) m.triangles.push_back({base, at(1, s), at(1, s + 1)});
  for (int r = 1; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      m.triangles.push_back({at(r, s), at(r + 1, s), at(r + 1, s + 1)});
      m.triangles.push_back({at(r, s), at(r + 1, s + 1), at(r, s + 1)});
    }
  for (int s = 0; s < segments; ++s) m.triangles.push_back({south, at(rings - 1, s + 1), at(rings - 1, s)});
}

// The meshes every test runs on: soups of big and small triangles, two
// closed spheres (solid mode has an interior to fill), a flat quad.
std::vector<Mesh> meshes() {
  std::mt19937 g(7);
  std::vector<Mesh> out;
  out.push_back(random_soup(g, 400 / kScale, 0.3));
  out.push_back(random_soup(g, 2000 / kScale, 0.03));
  Mesh spheres;
  add_sphere(spheres, V(0, 0, 0), 24, 48);
  add_sphere(spheres, V(2.5, 0.5, 0.3), 16, 32);
  out.push_back(spheres);
  Mesh quad;
  quad.positions = {V(0, 0, 0), V(4, 0, 0), V(4, 2, 0), V(0, 2, 0)};
  quad.triangles = {{0, 1, 2}, {0, 2, 3}};
  out.push_back(quad);
  return out;
}

// The definition, level by level and without any pruning: a child of an
// occupied box is occupied when some primitive overlaps it (the box grown by
// the pad), children in octant order under parents in Morton order.
OctreeMasks brute_force(const Mesh& mesh, int depth, Occupancy mode) {
  OctreeMasks t;
  t.bounds = {mesh.positions.front(), mesh.positions.front()};
  for (const V& p : mesh.positions) {
    t.bounds.min = t.bounds.min.cwiseMin(p);
    t.bounds.max = t.bounds.max.cwiseMax(p);
  }
  const double pad = occupancy_pad(t.bounds);
  std::vector<std::array<V, 3>> prims;
  if (mode == Occupancy::vertices)
    for (const V& p : mesh.positions) prims.push_back({p, p, p});
  else
    for (const auto& tri : mesh.triangles)
      prims.push_back({mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]]});
  std::vector<BoxCoord> level = {BoxCoord{}};
  for (int d = 0; d < depth; ++d) {
    std::vector<uint8_t> masks;
    std::vector<BoxCoord> next;
    for (const BoxCoord& c : level) {
      uint8_t mask = 0;
      for (uint32_t j = 0; j < 8; ++j) {
        const BoxCoord child{2 * c.x + (j & 1), 2 * c.y + (j >> 1 & 1), 2 * c.z + (j >> 2 & 1)};
        const Aabb b = t.box_bounds(d + 1, child);
        for (const auto& p : prims)
          if (triangle_overlaps_box(p[0], p[1], p[2], b.min, b.max, pad)) {
            mask |= uint8_t(1u << j);
            next.push_back(child);
            break;
          }
      }
      masks.push_back(mask);
    }
    t.masks.push_back(std::move(masks));
    level = std::move(next);
  }
  return t;
}

TEST(BuildTreeParallel, SameMasksForEveryThreadBudget) {
  for (const Mesh& mesh : meshes()) {
    for (Occupancy mode : {Occupancy::surface, Occupancy::solid, Occupancy::vertices}) {
      for (int depth : kDepths) {
        const OctreeMasks alone = build_tree(mesh, depth, mode);
        ASSERT_EQ(alone.depth(), depth);
        for (int helpers : kHelpers) {
          ThreadBudget budget(helpers);
          EXPECT_EQ(build_tree(mesh, depth, mode, {&budget, {}}), alone)
              << to_string(mode) << " depth " << depth << " helpers " << helpers;
          EXPECT_EQ(budget.free(), helpers) << "every slot given back";
        }
      }
    }
  }
}

TEST(BuildTreeParallel, EqualsBruteForceLevelByLevel) {
  std::mt19937 g(19);
  size_t occupied = 0, tested = 0;
  for (int round = 0; round < 4; ++round) {
    const Mesh mesh = random_soup(g, 60, round % 2 == 0 ? 0.5 : 0.1);
    for (Occupancy mode : {Occupancy::surface, Occupancy::vertices}) {
      const int depth = 5;
      const OctreeMasks want = brute_force(mesh, depth, mode);
      ThreadBudget budget(3);
      const OctreeMasks got = build_tree(mesh, depth, mode, {&budget, {}});
      ASSERT_EQ(got, want) << to_string(mode) << " round " << round;
      // Not vacuous: a good share of the candidate children is empty (the
      // surface's; the vertices' are sparse by nature).
      if (mode != Occupancy::surface) continue;
      for (int d = 1; d <= depth; ++d) {
        occupied += want.box_count(d);
        tested += 8 * want.box_count(d - 1);
      }
    }
  }
  const double rate = double(occupied) / double(tested);
  EXPECT_GT(rate, 0.3);
  EXPECT_LT(rate, 0.7);
}

TEST(BuildTreeParallel, NeverRunsMoreThreadsThanTheBudget) {
  Mesh mesh;
  add_sphere(mesh, V(0, 0, 0), 64 / kScale, 128 / kScale);
  for (int helpers : {0, 1, 3}) {
    ThreadBudget budget(helpers);
    std::mutex mu;
    std::set<std::thread::id> seen;
    BuildControl control{&budget, [&](uint64_t, uint64_t) {
                           const std::lock_guard lock(mu);
                           seen.insert(std::this_thread::get_id());
                           EXPECT_GE(budget.free(), 0);
                         }};
    build_tree(mesh, 7, Occupancy::surface, control);
    EXPECT_LE(seen.size(), size_t(helpers) + 1) << helpers;
    EXPECT_GE(seen.size(), 1u);
    EXPECT_EQ(budget.free(), helpers);
  }
  // A budget with no slot free (all taken by other work) still builds, alone.
  ThreadBudget empty(2);
  ASSERT_TRUE(empty.try_acquire());
  ASSERT_TRUE(empty.try_acquire());
  EXPECT_FALSE(empty.try_acquire());
  EXPECT_EQ(build_tree(mesh, 5, Occupancy::surface, {&empty, {}}), build_tree(mesh, 5, Occupancy::surface));
  empty.release();
  EXPECT_TRUE(empty.try_acquire());
}

TEST(BuildTreeParallel, ProgressStartsAtZeroGrowsAndEndsAtTotal) {
  for (const Mesh& mesh : meshes()) {
    for (Occupancy mode : {Occupancy::surface, Occupancy::solid}) {
      for (int helpers : {0, 2}) {
        ThreadBudget budget(helpers);
        std::vector<std::pair<uint64_t, uint64_t>> calls;  // never concurrent, so no lock
        build_tree(mesh, 6, mode, {&budget, [&](uint64_t done, uint64_t total) { calls.emplace_back(done, total); }});
        ASSERT_GE(calls.size(), 2u);
        EXPECT_EQ(calls.front().first, 0u);
        const uint64_t total = calls.front().second;
        EXPECT_GT(total, 0u);
        for (size_t k = 1; k < calls.size(); ++k) {
          EXPECT_EQ(calls[k].second, total);
          EXPECT_GT(calls[k].first, calls[k - 1].first) << "each part adds work";
        }
        EXPECT_EQ(calls.back().first, total);
      }
    }
  }
}

}  // namespace
}  // namespace octbake
