#include "octbake/motion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "seeded_random.h"

namespace octbake {
namespace {

TEST(Motion, SpunMatchesAngleAxisAndComposesAfterQ0) {
  const Eigen::Quaterniond q0(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));
  const Eigen::Vector3d w(0, 0, std::numbers::pi / 2);  // a quarter turn per second about z
  const Eigen::Quaterniond q = spun(q0, w, 1.0);
  const Eigen::Vector3d p(1, 0, 0);
  // The spin is about world z after q0: rotate by q0 first, then 90 degrees about z.
  const Eigen::Vector3d expected = Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ()) * (q0 * p);
  EXPECT_LT((q * p - expected).norm(), 1e-12);
  EXPECT_NEAR(q.norm(), 1.0, 1e-15);
  EXPECT_EQ(spun(q0, Eigen::Vector3d::Zero(), 5.0).coeffs(), q0.coeffs());
}

TEST(Motion, SpunFromFrameZeroDoesNotDrift) {
  // 10,000 frames of a fast spin: computed from frame 0 it stays a unit
  // quaternion and equals the closed form.
  const Eigen::Vector3d w(0.3, -1.1, 2.0);
  const double dt = 1.0 / 30.0;
  const Eigen::Quaterniond q = spun(Eigen::Quaterniond::Identity(), w, 10000 * dt);
  const Eigen::Quaterniond closed(Eigen::AngleAxisd(w.norm() * 10000 * dt, w.normalized()));
  EXPECT_LT(q.angularDistance(closed), 1e-9);
}

TEST(Motion, CameraPathInterpolatesAndHoldsOutside) {
  Camera base;
  base.fov_y_deg = 33;
  base.up = {0, 0, 1};
  const std::vector<CameraKey> path{{10, {0, 0, 0}, {1, 0, 0}}, {20, {10, 0, 0}, {11, 0, 0}}, {40, {10, 20, 0}, {10, 30, 0}}};
  EXPECT_EQ(camera_on_path(base, path, 0).position, Eigen::Vector3d(0, 0, 0));
  EXPECT_EQ(camera_on_path(base, path, 15).position, Eigen::Vector3d(5, 0, 0));
  EXPECT_EQ(camera_on_path(base, path, 15).look_at, Eigen::Vector3d(6, 0, 0));
  EXPECT_EQ(camera_on_path(base, path, 20).position, Eigen::Vector3d(10, 0, 0));
  EXPECT_EQ(camera_on_path(base, path, 30).position, Eigen::Vector3d(10, 10, 0));
  EXPECT_EQ(camera_on_path(base, path, 1000).look_at, Eigen::Vector3d(10, 30, 0));
  const Camera c = camera_on_path(base, path, 25);
  EXPECT_EQ(c.fov_y_deg, 33);
  EXPECT_EQ(c.up, Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(camera_on_path(base, {}, 5).position, base.position);
}

TEST(Motion, CameraPathIsPiecewiseLinearOnRandomPaths) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<CameraKey> path;
    int64_t f = int64_t(rng() % 101) - 50;
    for (int k = 0; k < 4; ++k) {
      path.push_back({f, test::random_point(rng, -100, 100), test::random_point(rng, -100, 100)});
      f += 1 + int64_t(rng() % 30);
    }
    const int64_t span = path.back().frame - path.front().frame;
    const int64_t frame = path.front().frame + int64_t(rng() % uint64_t(span + 1));
    const Camera c = camera_on_path(Camera{}, path, frame);
    size_t k = 0;
    while (path[k + 1].frame < frame) ++k;
    const double t = double(frame - path[k].frame) / double(path[k + 1].frame - path[k].frame);
    EXPECT_LT((c.position - (path[k].position + t * (path[k + 1].position - path[k].position))).norm(), 1e-9);
  }
}

}  // namespace
}  // namespace octbake
