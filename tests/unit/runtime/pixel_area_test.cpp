// pixel_area against a brute-force count of covered pixel centres, plus
// analytic face-on cases and extreme cameras.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "octbake/lod.h"
#include "pixel_area.h"

#include "seeded_random.h"

namespace octbake {
namespace {

using test::random_rotation;
using test::uniform01;

Eigen::Vector3d random_vector(std::mt19937& rng, double r) {
  return {r * (2 * uniform01(rng) - 1), r * (2 * uniform01(rng) - 1), r * (2 * uniform01(rng) - 1)};
}

OrientedBox make_box(Eigen::Vector3d center, Eigen::Vector3d half,
                     Eigen::Quaterniond q = Eigen::Quaterniond::Identity()) {
  OrientedBox box;
  box.center = center;
  box.axes = q.toRotationMatrix();
  box.half = half;
  return box;
}

// Does the ray cam + t * dir, t >= t_min, meet the box? (slabs in box frame)
bool ray_hits(const Eigen::Vector3d& cam, const Eigen::Vector3d& dir, double t_min, const OrientedBox& box) {
  const Eigen::Vector3d o = box.axes.transpose() * (cam - box.center);
  const Eigen::Vector3d d = box.axes.transpose() * dir;
  double lo = t_min, hi = INFINITY;
  for (int i = 0; i < 3; ++i) {
    if (d[i] == 0) {
      if (std::abs(o[i]) > box.half[i]) return false;
      continue;
    }
    const double t1 = (-box.half[i] - o[i]) / d[i], t2 = (box.half[i] - o[i]) / d[i];
    lo = std::max(lo, std::min(t1, t2));
    hi = std::min(hi, std::max(t1, t2));
  }
  return lo <= hi;
}

struct Coverage {
  int covered = 0;
  int boundary = 0;  // covered pixels with an uncovered 4-neighbour, and vice versa
};

// Casts one ray per pixel centre. The ray direction has unit depth, so its
// parameter is the distance along the view axis and t >= near is the near plane.
Coverage brute_force(const Camera& cam, const OrientedBox& box) {
  const Eigen::Vector3d f = (cam.look_at - cam.position).normalized();
  const Eigen::Vector3d r = f.cross(cam.up).normalized();
  const Eigen::Vector3d u = r.cross(f);
  const double ty = std::tan(cam.fov_y_deg * std::numbers::pi / 360), tx = ty * cam.viewport_w / cam.viewport_h;
  const int w = cam.viewport_w, h = cam.viewport_h;
  std::vector<char> hit(size_t(w) * h);
  Coverage c;
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const double x = (2 * (i + 0.5) / w - 1) * tx, y = (2 * (j + 0.5) / h - 1) * ty;
      hit[size_t(j) * w + i] = ray_hits(cam.position, f + x * r + y * u, cam.near_plane, box);
      c.covered += hit[size_t(j) * w + i];
    }
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const char v = hit[size_t(j) * w + i];
      const bool edge = (i > 0 && hit[size_t(j) * w + i - 1] != v) || (i + 1 < w && hit[size_t(j) * w + i + 1] != v) ||
                        (j > 0 && hit[size_t(j - 1) * w + i] != v) || (j + 1 < h && hit[size_t(j + 1) * w + i] != v);
      c.boundary += edge;
    }
  return c;
}

// Fewer rays in unoptimised (sanitizer) builds.
#ifdef NDEBUG
constexpr int kRuns = 300;
#else
constexpr int kRuns = 80;
#endif

TEST(PixelArea, MatchesCoveredPixelCentres) {
  std::mt19937 rng(2024);
  int seen = 0, empty = 0, clipped_by_near = 0, cases = 0;
  for (int run = 0; run < kRuns; ++run) {
    Camera cam;
    cam.position = random_vector(rng, 8);
    cam.look_at = random_vector(rng, 2);
    cam.up = random_vector(rng, 1);
    cam.fov_y_deg = 30 + 80 * uniform01(rng);
    cam.viewport_w = 64 + int(rng() % 137);
    cam.viewport_h = 48 + int(rng() % 103);
    cam.near_plane = run % 4 == 0 ? 2 + 4 * uniform01(rng) : 0.1;  // some boxes straddle the near plane
    const OrientedBox box = make_box(random_vector(rng, 3),
                                     {0.1 + 2 * uniform01(rng), 0.1 + 2 * uniform01(rng), 0.1 + 2 * uniform01(rng)},
                                     random_rotation(rng));
    const Eigen::Vector3d local = box.axes.transpose() * (cam.position - box.center);
    if ((local.cwiseAbs().array() <= box.half.array()).all()) continue;  // enclosing: tested below
    ++cases;
    const double area = pixel_area(cam, box);
    const Coverage c = brute_force(cam, box);
    EXPECT_NEAR(area, c.covered, 0.01 * c.covered + c.boundary + 4)
        << "run " << run << " boundary " << c.boundary << " viewport " << cam.viewport_w << "x" << cam.viewport_h;
    seen += c.covered > 100;
    empty += c.covered == 0;
    // The near plane matters: the count without it differs.
    Camera no_near = cam;
    no_near.near_plane = 1e-9;
    clipped_by_near += c.covered > 0 && brute_force(no_near, box).covered > c.covered + 50;
  }
  EXPECT_GT(seen, cases / 2);
  EXPECT_GT(empty, kRuns / 60);
  EXPECT_GT(clipped_by_near, kRuns / 60);
}

// A face-on box fully in view projects to a rectangle: its nearest face.
TEST(PixelArea, FaceOnRectangleIsExact) {
  for (const double distance : {5.0, 1e3, 1e9}) {
    Camera cam;
    cam.position = {0.25, -0.5, -distance};
    cam.look_at = {0.25, -0.5, 0};
    cam.fov_y_deg = 60;
    cam.viewport_w = 640;
    cam.viewport_h = 480;
    const OrientedBox box = make_box({0, 0, 0}, {1, 0.5, 2});
    const double ty = std::tan(std::numbers::pi / 6), tx = ty * 640 / 480;
    const double z = distance - 2;  // nearest face
    const double w = 2 * 1 / (z * tx) * 320, h = 2 * 0.5 / (z * ty) * 240;
    EXPECT_NEAR(pixel_area(cam, box), w * h, 1e-9 * w * h) << distance;
  }
}

TEST(PixelArea, EnclosingCameraIsTheWholeViewport) {
  Camera cam;
  cam.position = {0.1, 0.2, 0.3};
  cam.viewport_w = 320;
  cam.viewport_h = 200;
  EXPECT_EQ(pixel_area(cam, make_box({0, 0, 0}, {1, 1, 1})), 320.0 * 200);
  // Even a box smaller than the near distance.
  EXPECT_EQ(pixel_area(cam, make_box(cam.position, {0.01, 0.01, 0.01})), 320.0 * 200);
}

TEST(PixelArea, BehindOrBesideTheCameraIsZero) {
  Camera cam;  // at (0,0,-10) looking at the origin (+z)
  EXPECT_EQ(pixel_area(cam, make_box({0, 0, -20}, {1, 1, 1})), 0.0);
  EXPECT_EQ(pixel_area(cam, make_box({0, 0, -10.05}, {5, 5, 0.04})), 0.0);  // just behind, wide
  EXPECT_EQ(pixel_area(cam, make_box({100, 0, 0}, {1, 1, 1})), 0.0);      // outside the side planes
  // Wholly between the camera and the near plane.
  cam.near_plane = 1;
  EXPECT_EQ(pixel_area(cam, make_box({0, 0, -9.5}, {0.2, 0.2, 0.2})), 0.0);
}

TEST(PixelArea, ExtremeCamerasStayFiniteAndSane) {
  const OrientedBox straddling = make_box({0, 0, -10}, {3, 3, 3});
  const OrientedBox ahead = make_box({0, 0, 0}, {1, 1, 1});
  const OrientedBox far_away = make_box({0, 0, 1e9}, {1, 1, 1});
  const OrientedBox tilted = make_box({0.5, -0.3, 2}, {1, 2, 0.5},
                                      Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())));
  for (const double fov : {1e-6, 1.0, 60.0, 179.999})
    for (const auto& [w, h] : {std::pair{1, 1}, std::pair{16384, 16384}, std::pair{1920, 1080}})
      for (const OrientedBox* box : {&straddling, &ahead, &far_away, &tilted}) {
        Camera cam;
        cam.fov_y_deg = fov;
        cam.viewport_w = w;
        cam.viewport_h = h;
        const double area = pixel_area(cam, *box);
        EXPECT_TRUE(std::isfinite(area));
        EXPECT_GE(area, 0.0);
        EXPECT_LE(area, double(w) * h);
        if (box == &straddling) {
          EXPECT_EQ(area, double(w) * h);  // encloses the camera
        }
        if (box == &ahead && fov <= 1.0) {
          EXPECT_NEAR(area, double(w) * h, 1e-9 * w * h);  // fills a narrow view
        }
        if (box == &ahead && fov > 100) {
          EXPECT_GT(area, 0.0);
        }
      }
}

// A random camera and box for run `run`: sizes 1e-3..1e3, every fifth at a
// 1e7 offset, any fov and viewport, near planes 0 and tiny, some boxes flat.
struct RandomView {
  Camera cam;
  OrientedBox box;
};
RandomView random_view(std::mt19937& rng, int run) {
  const double offset = run % 5 == 0 ? 1e7 : 0, size = std::pow(10.0, -3 + 6 * uniform01(rng));
  RandomView v;
  v.cam.position = Eigen::Vector3d::Constant(offset) + random_vector(rng, 10 * size);
  v.cam.look_at = Eigen::Vector3d::Constant(offset) + random_vector(rng, size);
  v.cam.up = random_vector(rng, 1);
  v.cam.fov_y_deg = 10 + 150 * uniform01(rng);
  v.cam.viewport_w = 1 + int(rng() % 4000);
  v.cam.viewport_h = 1 + int(rng() % 3000);
  v.cam.near_plane = run % 3 == 0 ? 0 : 1e-3 * size;
  const double flat = run % 7 == 0 ? 1e-4 : 0.01;
  v.box = make_box(Eigen::Vector3d::Constant(offset) + random_vector(rng, 3 * size),
                   size * Eigen::Vector3d(flat + uniform01(rng), 0.01 + uniform01(rng), 0.01 + uniform01(rng)),
                   random_rotation(rng));
  return v;
}

// The fast path (the front faces projected, clipped in 2D) against clipping
// every face in 3D, over boxes in view, partly in view, far, tiny, huge and at
// 1e7 offsets: the same area to rounding.
TEST(PixelArea, ProjectedFacesEqualFrustumClipping) {
  std::mt19937 rng(77);
  int partial = 0, inside = 0, cases = 0;
  for (int run = 0; run < 20000; ++run) {
    const auto [cam, box] = random_view(rng, run);
    const double fast = pixel_area(cam, box), clipped = detail::pixel_area_clipped(cam, box);
    const double full = double(cam.viewport_w) * cam.viewport_h;
    ASSERT_NEAR(fast, clipped, 1e-9 * full + 1e-6) << "run " << run;
    ++cases;
    partial += fast > 0 && fast < 0.5 * full;
    inside += fast == full;
  }
  EXPECT_GT(partial, cases / 10);
  EXPECT_GT(inside, 0);
}

// The inscribed sphere's solid angle never exceeds the area, and is close to
// it for boxes well inside the view (else the bound would be useless).
TEST(PixelArea, LowerBoundHolds) {
  std::mt19937 rng(91);
  int useful = 0, cases = 0;
  for (int run = 0; run < 20000; ++run) {
    const auto [cam, box] = random_view(rng, run);
    const CameraView view(cam);
    const double bound = pixel_area_lower_bound(view, box), area = pixel_area(view, box);
    ASSERT_LE(bound, area) << "run " << run;
    ASSERT_GE(bound, 0.0);
    ++cases;
    useful += bound > 0.2 * area && area > 1;
  }
  EXPECT_GT(useful, cases / 20);
}

// The bound around the box's sphere never falls below the area; it is 0 for
// many boxes out of view and well below the viewport for many far ones (else
// it would be useless).
TEST(PixelArea, UpperBoundHolds) {
  std::mt19937 rng(93);
  int zero = 0, below_full = 0, cases = 0;
  for (int run = 0; run < 20000; ++run) {
    const auto [cam, box] = random_view(rng, run);
    const CameraView view(cam);
    const double bound = pixel_area_upper_bound(view, box), area = pixel_area(view, box);
    const double full = double(cam.viewport_w) * cam.viewport_h;
    ASSERT_GE(bound, area) << "run " << run;
    ASSERT_LE(bound, full) << "run " << run;
    ++cases;
    zero += bound == 0;
    below_full += bound > 0 && bound < 0.5 * full;
  }
  EXPECT_GT(zero, cases / 20);
  EXPECT_GT(below_full, cases / 20);
}

// A box around the camera fills the viewport even when the near plane lies
// beyond it; the upper bound must say so (not 0 for "behind the near plane").
TEST(PixelArea, UpperBoundOfABoxAroundTheCamera) {
  Camera cam;
  cam.position = {0, 0, 0};
  cam.look_at = {0, 0, -1};
  cam.near_plane = 5;
  cam.viewport_w = 320, cam.viewport_h = 200;
  const CameraView view(cam);
  for (const double size : {1e-3, 0.5, 2.0}) {
    const OrientedBox box = make_box({0.1 * size, -0.2 * size, 0.3 * size}, Eigen::Vector3d::Constant(size));
    const double area = pixel_area(view, box);
    EXPECT_EQ(area, 320.0 * 200.0) << size;
    EXPECT_GE(pixel_area_upper_bound(view, box), area) << size;
  }
}

// Boxes just outside a side of the view, a hair off: the bound stays above
// the area whichever way the corners round.
TEST(PixelArea, UpperBoundAtTheEdgesOfTheView) {
  std::mt19937 rng(95);
  int straddle = 0;
  for (int run = 0; run < 20000; ++run) {
    Camera cam;
    cam.position = random_vector(rng, 50);
    cam.look_at = cam.position + random_vector(rng, 1);
    cam.up = random_vector(rng, 1);
    cam.viewport_w = 64 + int(rng() % 512), cam.viewport_h = 64 + int(rng() % 512);
    cam.fov_y_deg = 20 + double(rng() % 120);
    const CameraView view(cam);
    // A box centred on a random direction at the edge of the frustum.
    const double z = std::ldexp(1.0 + double(rng() % 1000) / 1000, int(rng() % 20) - 5);
    const double side = (rng() % 2 ? 1 : -1) * (rng() % 2 ? view.tan_x() : view.tan_y());
    Eigen::Vector3d local(0, 0, z);
    local[rng() % 2 ? 0 : 1] = side * z * (1 + (double(rng() % 2001) - 1000) * 1e-12);
    OrientedBox box;
    box.center = cam.position + view.basis().transpose() * local;
    box.half = Eigen::Vector3d::Constant(z * std::ldexp(1.0, -int(rng() % 30)));
    const double bound = pixel_area_upper_bound(view, box), area = pixel_area(view, box);
    ASSERT_GE(bound, area) << "run " << run;
    straddle += area > 0;
  }
  EXPECT_GT(straddle, 100);
}

// Pixel area is a ratio of lengths: scaling the camera, the box and the near
// plane by a power of two (exact) must not change it, nor the lower bound,
// down to 2^-1000 and up to 2^1000, where squared lengths under- or
// overflow (a camera 1e300 from its target once looked nowhere).
TEST(PixelArea, ScaleFreeAtTheExtremesOfDouble) {
  std::mt19937 rng(17);
  int visible = 0;
  for (int run = 0; run < 2000; ++run) {
    const auto [cam, box] = random_view(rng, run);
    if (cam.near_plane == 0) continue;  // a tiny positive near plane does not scale
    const CameraView view(cam);
    const double area = pixel_area(view, box), bound = pixel_area_lower_bound(view, box);
    const double upper = pixel_area_upper_bound(view, box);
    const double full = double(cam.viewport_w) * cam.viewport_h;
    visible += area > 1;
    for (const int e : {-100, 100, -1000, -600, 600, 1000}) {
      const double s = std::ldexp(1.0, e);
      Camera c = cam;
      c.position *= s, c.look_at *= s, c.near_plane *= s;
      OrientedBox b = box;
      b.center *= s, b.half *= s;
      const CameraView v(c);
      EXPECT_NEAR(pixel_area(v, b), area, 1e-9 * full) << "run " << run << ", scale 2^" << e;
      EXPECT_NEAR(pixel_area_lower_bound(v, b), bound, 1e-9 * full) << "run " << run << ", scale 2^" << e;
      EXPECT_NEAR(pixel_area_upper_bound(v, b), upper, 1e-9 * full) << "run " << run << ", scale 2^" << e;
    }
  }
  EXPECT_GT(visible, 100);
}

TEST(PixelArea, UpAlongTheViewDirectionStillWorks) {
  Camera cam;
  cam.position = {0, 10, 0};
  cam.look_at = {0, 0, 0};
  cam.up = {0, 1, 0};  // parallel to the view direction
  cam.viewport_w = cam.viewport_h = 100;
  const OrientedBox box = make_box({0, 0, 0}, {1, 1, 1});
  const double area = pixel_area(cam, box);
  Camera sane = cam;
  sane.up = {0, 0, 1};
  // Square viewport, box centred face-on: the roll does not change the area.
  EXPECT_NEAR(area, pixel_area(sane, box), 1e-9 * area);
  EXPECT_GT(area, 0.0);
}

}  // namespace
}  // namespace octbake
