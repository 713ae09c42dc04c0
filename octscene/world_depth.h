// What each WorldTree depth would cost a scene, counted from its objects'
// boxes at frame 0 and one timestep later, so that `octscene plan` can show
// the trade and suggest a depth. The depth is the scene author's choice, and
// a bad one costs 5-10x a frame (a generated 100k-object scene with sizes
// over 400x: 16 ms at depth 7, 99 ms at 10). The pair tests and the
// per-object work are the same at every depth, so only the WorldTree's share
// is estimated.
#pragma once
#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "octbake/octree.h"
#include "run.h"
#include "scene.h"

namespace octbake::scene {

struct WorldDepthCost {
  int depth = 0;
  uint64_t memberships = 0;  // (object, cell) pairs the WorldTree stores
  uint64_t overflow = 0;     // objects over WorldTree::kMaxCells cells: paired with everything
  // Cells are counted (a sort of the memberships) only up to
  // kCountedMemberships memberships; a depth past that is never suggested.
  bool counted = false;
  uint64_t cells = 0;            // occupied cells
  uint64_t cell_pairs = 0;       // pairs of objects sharing a cell, once per cell they share
  uint64_t scan_checks = 0;      // the pair scan: cell_pairs of cells up to 32, k log2 k for larger (swept) ones
  uint64_t overflow_checks = 0;  // pairs of overflow objects with the rest (or their coarse cells)
  double reinsertions = 0;       // expected objects changing cells in a frame
  double cell_changes = 0;       // expected cells entered plus left in a frame
  double estimate_us = 0;        // the WorldTree's share of a frame, estimated (kCost* below)
};

struct WorldDepthPlan {
  std::vector<WorldDepthCost> depths;  // 0..10
  // The shallowest counted depth whose estimate is within 10% or 2 us of the
  // lowest (suggestion_limit): a deeper one holds more cells (memory,
  // start-up) for a gain the estimate cannot resolve.
  int suggested = 0;
};
inline double suggestion_limit(double lowest_us) { return std::max(lowest_us * 1.1, lowest_us + 2); }

inline constexpr uint64_t kCountedMemberships = uint64_t(1) << 24;  // 128 MB of sort keys
// Nanoseconds per unit of work, from per-depth sweeps of eight scenes (the
// bundled four and generated ones of 1k, 10k and 100k objects, uniform and
// 400x mixed sizes) on a 2-core EPYC VM: what a frame gained or lost between
// neighbouring depths over what the counts changed. A cell change is costly
// (a hash lookup in a table of up to millions of cells, a cell made or
// freed); the ranking, not the absolute value, is what the suggestion uses.
inline constexpr double kCostScanCheck = 10, kCostOverflowCheck = 2, kCostCellChange = 300, kCostReinsertion = 100;

// `now[i]` and `next[i]`: object i's world box at frame 0 and one timestep on.
WorldDepthPlan plan_world_depth(const Aabb& world, std::span<const Aabb> now, std::span<const Aabb> next,
                                uint64_t counted_memberships = kCountedMemberships);
// The same for a scene: each object's box from its tree's bounds, its pose,
// and its velocity and angular velocity over one timestep.
WorldDepthPlan plan_world_depth(const Scene& scene, const SceneModels& models);

}  // namespace octbake::scene
