// Seeded random values for tests, made by hand from raw std::mt19937 output:
// the standard distributions differ between standard libraries, these don't.
#pragma once
#include <Eigen/Geometry>
#include <bit>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

namespace octbake::test {

// Uniform in [0, 1) with 53 random bits.
inline double uniform01(std::mt19937& rng) {
  const uint64_t hi = rng() >> 5, lo = rng() >> 6;
  return double((hi << 26) | lo) * 0x1p-53;
}

// Uniform in [lo, hi) from one 32-bit draw.
inline double uniform(std::mt19937& g, double lo, double hi) { return lo + (hi - lo) * (g() / 4294967296.0); }

inline Eigen::Vector3d random_point(std::mt19937& g, double lo, double hi) {
  return {uniform(g, lo, hi), uniform(g, lo, hi), uniform(g, lo, hi)};
}

// Uniform on SO(3) (Shoemake, "Uniform random rotations", Graphics Gems III).
inline Eigen::Quaterniond random_rotation(std::mt19937& rng) {
  const double u1 = uniform01(rng), u2 = 2 * std::numbers::pi * uniform01(rng),
               u3 = 2 * std::numbers::pi * uniform01(rng);
  return Eigen::Quaterniond(std::sqrt(u1) * std::cos(u3), std::sqrt(1 - u1) * std::sin(u2),
                            std::sqrt(1 - u1) * std::cos(u2), std::sqrt(u1) * std::sin(u3));
}

// Child masks of a random tree, breadth first (OctreeMasks::masks): each
// child present with probability 3/4, so a box may end up with none.
inline std::vector<std::vector<uint8_t>> random_masks(std::mt19937& rng, int depth) {
  std::vector<std::vector<uint8_t>> masks;
  uint64_t boxes = 1;
  for (int d = 0; d < depth; ++d) {
    std::vector<uint8_t> level(boxes);
    boxes = 0;
    for (auto& m : level) {
      m = uint8_t((rng() | rng()) & 0xFF);
      boxes += std::popcount(m);
    }
    masks.push_back(std::move(level));
  }
  return masks;
}

}  // namespace octbake::test
