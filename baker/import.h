// Mesh import through assimp: triangulated, node transforms applied,
// identical vertices joined. The only file that knows about assimp.
#pragma once
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "octbake/baker.h"  // Mesh
#include "octbake/result.h"

namespace octbake {

// Refuses (invalid_argument / io_error / not_found, message = reason only,
// without the path): unreadable or malformed file, empty scene, no triangles
// (points or lines only), NaN or infinite coordinates. `files_read`, when
// given, gets every file assimp opened (absolute, normalised, deduplicated,
// in first-opened order), recorded through its IOSystem.
Result<Mesh> import_mesh(const std::string& path, std::vector<std::string>* files_read = nullptr);

// Keeps only the positions that `triangles` use, refuses NaN or infinite
// ones and out-of-range indices, joins exactly identical positions: the
// mesh preparation import_mesh does after reading a file.
Result<Mesh> prepare_mesh(const std::vector<Eigen::Vector3d>& positions,
                          const std::vector<std::array<uint32_t, 3>>& triangles);

}  // namespace octbake
