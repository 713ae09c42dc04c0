#include "octbake/pose.h"

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace octbake {
namespace {

// std::nextafter(x, +inf) inline (the libm call was a tenth of a frame with
// many spinning objects): the next double up, for every x.
double next_up(double x) {
  if (std::isnan(x) || x == std::numeric_limits<double>::infinity()) return x;
  if (x == 0) return std::numeric_limits<double>::denorm_min();
  const uint64_t bits = std::bit_cast<uint64_t>(x);
  return std::bit_cast<double>(x > 0 ? bits + 1 : bits - 1);
}
double next_down(double x) { return -next_up(-x); }

}  // namespace

OrientedBox place(const Aabb& local, const Pose& pose) {
  OrientedBox box;
  box.center = pose.apply(0.5 * (local.min + local.max));
  box.axes = pose.rotation.toRotationMatrix();
  box.half = (0.5 * pose.scale) * (local.max - local.min).cwiseAbs();
  return box;
}

Aabb world_bounds(const OrientedBox& box) {
  // Extent along each world axis; the relative grow absorbs the rounding of
  // the rotation matrix and of this sum, one ulp outwards the rounding of +/-.
  Eigen::Vector3d extent = box.axes.cwiseAbs() * box.half;
  extent *= 1.0 + 1e-12;
  Aabb out;
  for (int i = 0; i < 3; ++i) {
    out.min[i] = next_down(box.center[i] - extent[i]);
    out.max[i] = next_up(box.center[i] + extent[i]);
  }
  return out;
}

}  // namespace octbake
