// Exact, conservative triangle-box overlap (separating axis test), used by
// surface and solid occupancy.
#pragma once
#include <Eigen/Core>

namespace octbake {

// True when triangle (a, b, c) overlaps the closed box [lo, hi], the box grown
// by `pad` on every side to absorb rounding. Degenerate triangles (segments,
// points) are handled: they still occupy the boxes they touch.
bool triangle_overlaps_box(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                           const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double pad);

}  // namespace octbake
