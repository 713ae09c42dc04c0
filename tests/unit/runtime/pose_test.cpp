// world_bounds: the world AABB of a placed box, rounded outwards by one ulp
// (an inline step, checked here against std::nextafter) after a relative grow.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <limits>
#include <random>

#include "octbake/pose.h"

#include "seeded_random.h"

namespace octbake {
namespace {

// The same formula with the library's nextafter.
Aabb reference_bounds(const OrientedBox& box) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Eigen::Vector3d extent = box.axes.cwiseAbs() * box.half;
  extent *= 1.0 + 1e-12;
  Aabb out;
  for (int i = 0; i < 3; ++i) {
    out.min[i] = std::nextafter(box.center[i] - extent[i], -kInf);
    out.max[i] = std::nextafter(box.center[i] + extent[i], kInf);
  }
  return out;
}

bool same_bits(const Aabb& a, const Aabb& b) {
  for (int i = 0; i < 3; ++i)
    if (std::bit_cast<uint64_t>(a.min[i]) != std::bit_cast<uint64_t>(b.min[i]) ||
        std::bit_cast<uint64_t>(a.max[i]) != std::bit_cast<uint64_t>(b.max[i]))
      return false;
  return true;
}

TEST(WorldBounds, OneUlpOutwardsLikeNextafter) {
  std::mt19937 rng(11);
  const double specials[] = {0.0, -0.0, std::numeric_limits<double>::denorm_min(), -std::numeric_limits<double>::min(),
                             1e-300, -1e300, 1e7, -1e7, std::numeric_limits<double>::max(),
                             -std::numeric_limits<double>::denorm_min(), std::numeric_limits<double>::infinity(),
                             -std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::max()};
  int cases = 0;
  for (int run = 0; run < 20000; ++run) {
    OrientedBox box;
    const double mag = std::pow(10.0, -8 + 16 * test::uniform01(rng));
    for (int i = 0; i < 3; ++i) {
      box.center[i] = run % 7 == 0 ? specials[(run / 7 + i) % std::size(specials)] : mag * (2 * test::uniform01(rng) - 1);
      box.half[i] = run % 11 == 0 ? 0.0 : mag * test::uniform01(rng);
    }
    box.axes = test::random_rotation(rng).toRotationMatrix();
    if (run % 13 == 0) box.axes.setIdentity();
    ASSERT_TRUE(same_bits(world_bounds(box), reference_bounds(box))) << "run " << run;
    ++cases;
  }
  EXPECT_EQ(cases, 20000);
  // Infinite extents stay infinite, outwards.
  OrientedBox huge;
  huge.center.setZero();
  huge.axes.setIdentity();
  huge.half = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  EXPECT_TRUE(same_bits(world_bounds(huge), reference_bounds(huge)));
}

}  // namespace
}  // namespace octbake
