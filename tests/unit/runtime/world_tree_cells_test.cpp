// WorldTree::cell_range (two bounds per vector lane pair) against the scalar
// cell map it must equal bit for bit: queries map their boxes with the scalar
// one, and a pair or a query answer is only never missed when both agree.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <random>

#include "octbake/world_tree.h"

namespace octbake {
namespace {

double unit(std::mt19937& rng) { return double(rng() >> 8) * (1.0 / 16777216.0); }

// The map as world_tree.h defines it: t = (p - world.min) * (side / extent),
// side - 1 when t >= side, else the truncation of t when t > 0, else 0.
uint16_t scalar_cell(const Aabb& world, int depth, double p, int k) {
  const double side = double(1u << depth);
  const double inv = side / (world.max[k] - world.min[k]);
  const double t = (p - world.min[k]) * inv;
  return t >= side ? uint16_t(side - 1) : t > 0 ? uint16_t(t) : uint16_t(0);
}

TEST(WorldTreeCells, RangeIsTheScalarCellMap) {
  std::mt19937 rng(5);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  int boundary_hits = 0, clamped = 0;
  for (int world_run = 0; world_run < 200; ++world_run) {
    // Worlds from 1e-3 to 1e4 wide, some 1e6 (or 1e9) from the origin.
    const double width = std::pow(10.0, -3 + 7 * unit(rng));
    const double offset = world_run % 3 == 0 ? 0.0 : std::pow(10.0, 9 * unit(rng)) * (unit(rng) < 0.5 ? -1 : 1);
    Aabb world;
    for (int k = 0; k < 3; ++k) {
      world.min[k] = offset + width * (unit(rng) - 1);
      world.max[k] = world.min[k] + width * (0.25 + unit(rng));
    }
    const int depth = world_run % 11;
    const WorldTree tree(world, depth);
    const double side = double(1u << depth);
    for (int run = 0; run < 500; ++run) {
      Aabb box;
      for (int k = 0; k < 3; ++k) {
        const double extent = world.max[k] - world.min[k];
        double a, b;
        switch (run % 5) {
          case 0:  // exactly on cell boundaries (as rounding gives them)
            a = world.min[k] + extent * std::floor(unit(rng) * (side + 1)) / side;
            b = world.min[k] + extent * std::floor(unit(rng) * (side + 1)) / side;
            break;
          case 1:  // reaching outside the world, or to infinity
            a = world.min[k] - extent * unit(rng) * (run % 10 == 1 ? kInf : 2.0);
            b = world.max[k] + extent * unit(rng) * (run % 20 == 1 ? kInf : 2.0);
            break;
          default:
            a = world.min[k] + extent * (1.4 * unit(rng) - 0.2);
            b = world.min[k] + extent * (1.4 * unit(rng) - 0.2);
        }
        if (std::isnan(a)) a = -kInf;  // 0 * inf
        if (std::isnan(b)) b = kInf;
        box.min[k] = std::min(a, b);
        box.max[k] = std::max(a, b);
      }
      const WorldTree::CellRange r = tree.cell_range(box);
      uint64_t count = 1;
      for (int k = 0; k < 3; ++k) {
        const uint16_t lo = scalar_cell(world, depth, box.min[k], k), hi = scalar_cell(world, depth, box.max[k], k);
        ASSERT_EQ(r.lo[k], lo) << "world " << world_run << " box " << run << " axis " << k << " min " << box.min[k];
        ASSERT_EQ(r.hi[k], hi) << "world " << world_run << " box " << run << " axis " << k << " max " << box.max[k];
        count *= uint64_t(hi) - lo + 1;
        const double t = (box.max[k] - world.min[k]) * (side / (world.max[k] - world.min[k]));
        boundary_hits += t == std::floor(t) && t > 0 && t < side;
        clamped += t >= side;
      }
      ASSERT_EQ(r.overflow, count > WorldTree::kMaxCells);
    }
  }
  // The cases that can go wrong were reached.
  EXPECT_GT(boundary_hits, 1000);
  EXPECT_GT(clamped, 1000);
}

}  // namespace
}  // namespace octbake
