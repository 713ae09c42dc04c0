// A seeded triangle soup for builder tests: `triangles` triangles, each with
// one corner uniform in [-1, 1]^3 and the others within `size` of it.
#pragma once
#include <random>

#include "import.h"
#include "seeded_random.h"

namespace octbake::test {

inline Mesh random_soup(std::mt19937& g, int triangles, double size) {
  Mesh m;
  for (int i = 0; i < triangles; ++i) {
    const Eigen::Vector3d a = random_point(g, -1, 1);
    for (int k = 0; k < 3; ++k) m.positions.push_back(k == 0 ? a : Eigen::Vector3d(a + random_point(g, -size, size)));
    const uint32_t base = uint32_t(3 * i);
    m.triangles.push_back({base, base + 1, base + 2});
  }
  return m;
}

}  // namespace octbake::test
