// Rigid placement of a mesh in the world: world = position + rotation * (scale * p).
#pragma once
#include <Eigen/Geometry>
#include <cmath>

#include "octbake/octree.h"
#include "octbake/export.h"

namespace octbake {

struct Pose {
  Eigen::Vector3d position{0, 0, 0};  // where the mesh's origin goes (double: huge worlds)
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  // unit
  double scale = 1.0;                 // uniform, > 0

  Eigen::Vector3d apply(const Eigen::Vector3d& p) const { return position + rotation * (scale * p); }
};

// The rotation matrix of q / |q|. Poses are accepted with |q| within 1e-6
// of 1, and toRotationMatrix() of such a q scales and shears by up to
// ~2e-6, far past the pair test's 1e-9 paddings: a touching pair could be
// missed. Within 1e-12 of unit the matrix is used as is (the paddings cover
// it, and the usual, nearly unit quaternion keeps its bits).
inline Eigen::Matrix3d rotation_matrix(const Eigen::Quaterniond& q) {
  const double n2 = q.squaredNorm();
  return std::abs(n2 - 1) <= 1e-12 ? q.toRotationMatrix() : q.normalized().toRotationMatrix();
}

// A box in world space with its own axes (a posed local Aabb).
struct OrientedBox {
  Eigen::Vector3d center{0, 0, 0};
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // columns: unit axes
  Eigen::Vector3d half{0, 0, 0};                        // half extents, >= 0
};

OCTBAKE_API OrientedBox place(const Aabb& local, const Pose& pose);
// World axis-aligned bounds of a placed box.
OCTBAKE_API Aabb world_bounds(const OrientedBox& box);

}  // namespace octbake
