#include "world_depth.h"

#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>

#include "octbake/motion.h"
#include "octbake/pose.h"
#include "octbake/world_tree.h"

namespace octbake::scene {

namespace {

uint64_t cells_in(const WorldTree::CellRange& r) {
  uint64_t cells = 1;
  for (int k = 0; k < 3; ++k) cells *= uint64_t(r.hi[k] - r.lo[k]) + 1;
  return cells;
}

// Sorts `keys` (packed cells, one per membership) and adds each cell's
// occupants' pairs to c.
void count_cells(std::vector<uint64_t>& keys, WorldDepthCost& c) {
  std::sort(keys.begin(), keys.end());
  for (size_t a = 0; a < keys.size();) {
    size_t b = a + 1;
    while (b < keys.size() && keys[b] == keys[a]) ++b;
    const uint64_t k = b - a;
    ++c.cells;
    c.cell_pairs += k * (k - 1) / 2;
    // WorldTree sweeps a cell of more than 32 by box min x instead.
    c.scan_checks += k <= 32 ? k * (k - 1) / 2 : k * uint64_t(std::bit_width(k - 1));
    a = b;
  }
}

}  // namespace

WorldDepthPlan plan_world_depth(const Aabb& world, std::span<const Aabb> now, std::span<const Aabb> next,
                                uint64_t counted_memberships) {
  assert(now.size() == next.size());
  const uint64_t n = now.size();
  WorldDepthPlan plan;
  std::vector<WorldTree::CellRange> ranges(n);
  std::vector<uint64_t> keys;
  for (int depth = 0; depth <= 10; ++depth) {
    const WorldTree grid(world, depth);
    Eigen::Vector3d cells_per_unit;
    for (int k = 0; k < 3; ++k) cells_per_unit[k] = double(1 << depth) / (world.max[k] - world.min[k]);
    WorldDepthCost c;
    c.depth = depth;
    for (uint64_t i = 0; i < n; ++i) {
      const WorldTree::CellRange& r = ranges[i] = grid.cell_range(now[i]);
      if (r.overflow) {
        ++c.overflow;
        continue;
      }
      const uint64_t cells = cells_in(r);
      c.memberships += cells;
      // Each face crosses, on average, as many cell boundaries as it moves
      // cell widths; each crossing enters or leaves one slab of the range.
      double crossings = 0, changes = 0;
      for (int k = 0; k < 3; ++k) {
        const double width = double(r.hi[k] - r.lo[k]) + 1;
        double moved =
            (std::abs(next[i].min[k] - now[i].min[k]) + std::abs(next[i].max[k] - now[i].max[k])) * cells_per_unit[k];
        if (!(moved < 2 * width)) moved = 2 * width;  // all of it changes (also inf or NaN at 1e308)
        crossings += moved;
        changes += moved * (double(cells) / width);
      }
      c.reinsertions += std::min(1.0, crossings);
      c.cell_changes += std::min(changes, 2.0 * double(cells));
    }
    c.counted = c.memberships <= counted_memberships;
    if (c.counted) {
      keys.clear();
      keys.reserve(c.memberships);
      for (const WorldTree::CellRange& r : ranges) {
        if (r.overflow) continue;
        for (uint64_t z = r.lo[2]; z <= r.hi[2]; ++z)
          for (uint64_t y = r.lo[1]; y <= r.hi[1]; ++y)
            for (uint64_t x = r.lo[0]; x <= r.hi[0]; ++x) keys.push_back(x | y << 16 | z << 32);
      }
      count_cells(keys, c);
    }
    // Few overflow objects are paired with every object; past kCoarseFrom
    // through coarse cells, at most ~20 checks an object (the weights of
    // WorldTree's own cost guard: 16 per listed coarse cell, 4 per lookup).
    const uint64_t plain = c.overflow * n;
    c.overflow_checks = plain < WorldTree::kCoarseFrom ? plain : std::min(plain, 20 * n);
    c.estimate_us = (kCostScanCheck * double(c.scan_checks) + kCostOverflowCheck * double(c.overflow_checks) +
                     kCostCellChange * c.cell_changes + kCostReinsertion * c.reinsertions) / 1000;
    plan.depths.push_back(c);
  }
  double best = INFINITY;
  for (const WorldDepthCost& c : plan.depths)
    if (c.counted) best = std::min(best, c.estimate_us);
  for (const WorldDepthCost& c : plan.depths)
    if (c.counted && c.estimate_us <= suggestion_limit(best)) {
      plan.suggested = c.depth;
      break;
    }
  return plan;
}

WorldDepthPlan plan_world_depth(const Scene& scene, const SceneModels& models) {
  std::vector<Aabb> now(scene.objects.size()), next(scene.objects.size());
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& o = scene.objects[i];
    const Aabb& local = models.trees[models.tree_of_object[i]].bounds();
    now[i] = world_bounds(place(local, o.pose));
    Pose moved = o.pose;
    moved.position += o.velocity * scene.timestep;
    moved.rotation = spun(o.pose.rotation, o.angular_velocity, scene.timestep);
    next[i] = world_bounds(place(local, moved));
  }
  return plan_world_depth(scene.world, now, next);
}

}  // namespace octbake::scene
