#include "octbake/motion.h"

#include <algorithm>

namespace octbake {

Eigen::Quaterniond spun(const Eigen::Quaterniond& q0, const Eigen::Vector3d& angular_velocity, double seconds) {
  const double rate = angular_velocity.norm();
  if (rate == 0) return q0;
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(rate * seconds, angular_velocity / rate));
  return (turn * q0).normalized();
}

Camera camera_on_path(const Camera& base, std::span<const CameraKey> path, int64_t frame) {
  Camera camera = base;
  if (path.empty()) return camera;
  if (frame <= path.front().frame) {
    camera.position = path.front().position;
    camera.look_at = path.front().look_at;
    return camera;
  }
  if (frame >= path.back().frame) {
    camera.position = path.back().position;
    camera.look_at = path.back().look_at;
    return camera;
  }
  // First key after `frame`; the one before it is <= frame.
  const auto next = std::upper_bound(path.begin(), path.end(), frame,
                                     [](int64_t f, const CameraKey& k) { return f < k.frame; });
  const CameraKey& k1 = *next;
  const CameraKey& k0 = *(next - 1);
  const double t = double(frame - k0.frame) / double(k1.frame - k0.frame);
  camera.position = k0.position + t * (k1.position - k0.position);
  camera.look_at = k0.look_at + t * (k1.look_at - k0.look_at);
  return camera;
}

}  // namespace octbake
