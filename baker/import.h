// Mesh import through assimp: triangulated, node transforms applied,
// identical vertices joined. The only file that knows about assimp.
#pragma once
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "octbake/result.h"

namespace octbake {

struct Mesh {
  std::vector<Eigen::Vector3d> positions;
  std::vector<std::array<uint32_t, 3>> triangles;
};

// Refuses (invalid_argument / io_error / not_found, message = reason only,
// without the path): unreadable or malformed file, empty scene, no triangles
// (points or lines only), NaN or infinite coordinates.
Result<Mesh> import_mesh(const std::string& path);

}  // namespace octbake
