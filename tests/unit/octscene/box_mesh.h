// An axis-aligned box as a closed 12-triangle mesh, for the octscene tests.
#pragma once
#include <Eigen/Core>
#include <cstdint>

#include "import.h"

namespace octbake::scene::testing {

inline Mesh box_mesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  Mesh m;
  for (int j = 0; j < 8; ++j) m.positions.emplace_back((j & 1) ? hi.x() : lo.x(), (j & 2) ? hi.y() : lo.y(), (j & 4) ? hi.z() : lo.z());
  for (uint32_t bit : {1u, 2u, 4u}) {
    const uint32_t u = bit == 1 ? 2 : 1, v = bit == 4 ? 2 : 4;
    for (uint32_t side : {0u, bit}) {
      m.triangles.push_back({side, side | u, side | u | v});
      m.triangles.push_back({side, side | u | v, side | v});
    }
  }
  return m;
}

}  // namespace octbake::scene::testing
