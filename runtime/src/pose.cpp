#include "octbake/pose.h"

#include <cmath>
#include <limits>

namespace octbake {

OrientedBox place(const Aabb& local, const Pose& pose) {
  OrientedBox box;
  box.center = pose.apply(0.5 * (local.min + local.max));
  box.axes = pose.rotation.toRotationMatrix();
  box.half = (0.5 * pose.scale) * (local.max - local.min).cwiseAbs();
  return box;
}

Aabb world_bounds(const OrientedBox& box) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  // Extent along each world axis; the relative grow absorbs the rounding of
  // the rotation matrix and of this sum, nextafter the rounding of +/-.
  Eigen::Vector3d extent = box.axes.cwiseAbs() * box.half;
  extent *= 1.0 + 1e-12;
  Aabb out;
  for (int i = 0; i < 3; ++i) {
    out.min[i] = std::nextafter(box.center[i] - extent[i], -kInf);
    out.max[i] = std::nextafter(box.center[i] + extent[i], kInf);
  }
  return out;
}

}  // namespace octbake
