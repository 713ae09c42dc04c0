// Scripted motion shared by the simulation layer (World) and the tools:
// spinning objects and a camera path (docs/interface.md, scene keys
// "angular_velocity" and "camera_path"). Every value is computed from frame 0
// (never accumulated), so nothing drifts and runs are bit-identical.
#pragma once
#include <Eigen/Geometry>
#include <cstdint>
#include <span>

#include "octbake/lod.h"
#include "octbake/export.h"

namespace octbake {

// Orientation after `seconds` of spinning at `angular_velocity` (radians per
// second about world axes through the object's position), applied after q0:
// q(t) = R(w, |w| t) * q0. Zero angular velocity returns q0 unchanged.
OCTBAKE_API Eigen::Quaterniond spun(const Eigen::Quaterniond& q0, const Eigen::Vector3d& angular_velocity, double seconds);

// One key of a camera path: at `frame` the camera is at `position` looking at
// `look_at`.
struct CameraKey {
  int64_t frame = 0;
  Eigen::Vector3d position{0, 0, 0};
  Eigen::Vector3d look_at{0, 0, 1};
};

// `base` with position and look_at interpolated linearly between the keys
// around `frame` (frames strictly ascending): the first key's values before
// it, the last key's after it; up, fov, viewport, near and far stay those of
// `base`. An empty path returns `base`.
OCTBAKE_API Camera camera_on_path(const Camera& base, std::span<const CameraKey> path, int64_t frame);

}  // namespace octbake
