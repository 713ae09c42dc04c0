// Pixel area (docs/interface.md section 7) and the depth policies built on it.
#pragma once
#include <Eigen/Core>
#include <span>
#include <vector>

#include "octbake/pose.h"
#include "octbake/export.h"

namespace octbake {

struct Camera {
  Eigen::Vector3d position{0, 0, -10};
  Eigen::Vector3d look_at{0, 0, 0};
  Eigen::Vector3d up{0, 1, 0};
  double fov_y_deg = 60;
  int viewport_w = 1920, viewport_h = 1080;
  double near_plane = 0.1, far_plane = 2000;
};

// Area in pixels of the convex outline of `box` projected through `camera`:
// only the part in front of the near plane counts, clipped to the viewport;
// 0 when wholly outside the view; the whole viewport when the box encloses the
// camera. Always finite and >= 0, and scale-free: scaling the camera, its
// near plane and the box by a power of two keeps the area (coordinates up
// to 2^1000 and down to 2^-1000).
// Camera basis: forward = look_at - position (look_at == position looks down
// -z); right = forward x up; an up parallel to forward (or zero) is replaced
// by the world axis least aligned with forward. fov_y_deg is clamped into
// (0, 180); the horizontal fov follows from the viewport aspect; a near plane
// <= 0 acts as a tiny positive one. The far plane is ignored. A viewport with
// a side <= 0 gives 0.
OCTBAKE_API double pixel_area(const Camera& camera, const OrientedBox& box);

// A camera prepared for many pixel_area calls: its basis and field-of-view
// terms are computed once (pixel_area(camera, box) builds one per call).
// Same results as pixel_area(camera, box), bit for bit.
class OCTBAKE_API CameraView {
 public:
  explicit CameraView(const Camera& camera);
  const Camera& camera() const { return camera_; }
  const Eigen::Matrix3d& basis() const { return basis_; }  // rows: right, up, forward
  double tan_x() const { return tan_x_; }                  // tan of half the horizontal fov
  double tan_y() const { return tan_y_; }
  double width() const { return width_; }
  double height() const { return height_; }

 private:
  Camera camera_;
  Eigen::Matrix3d basis_;
  double tan_x_ = 0, tan_y_ = 0, width_ = 0, height_ = 0;
};
OCTBAKE_API double pixel_area(const CameraView& view, const OrientedBox& box);
// A lower bound of pixel_area(view, box) at a fraction of its cost: the
// solid angle of the box's inscribed sphere when that sphere lies wholly
// inside the view frustum (its image is then inside the viewport and inside
// the box's outline, and projecting onto the image plane never shrinks solid
// angle), 0 otherwise. Lets a policy that only needs to know "at least this
// many pixels" skip the exact area.
OCTBAKE_API double pixel_area_lower_bound(const CameraView& view, const OrientedBox& box);
// An upper bound of pixel_area(view, box), as cheap: 0 when a sphere around
// the box lies wholly outside one plane of the view frustum; else, when that
// sphere is in front of the near plane, the viewport's part of the image of
// the cube around it (a rectangle: x / z and y / z are monotone over it);
// else the whole viewport. Lets a policy that only needs to know "at most
// this many pixels" (far objects, objects out of view) skip the exact area.
OCTBAKE_API double pixel_area_upper_bound(const CameraView& view, const OrientedBox& box);

enum class LodPolicy { fixed, thesis, screen };
inline constexpr LodPolicy kLodPolicies[] = {LodPolicy::fixed, LodPolicy::thesis, LodPolicy::screen};
// "fixed", "thesis", "screen": the names command lines and JSON use.
OCTBAKE_API const char* to_string(LodPolicy policy);

struct LodSettings {
  LodPolicy policy = LodPolicy::screen;
  int min_depth = 1;
  int max_depth = 12;  // clamped per object to its baked/loaded depth
  double pixel_tolerance = 1.0;
};

// floor(area / (a_min + a_max) * max_depth) + min_depth, clamped to
// [min_depth, max_depth]; min_depth when a_min + a_max == 0.
OCTBAKE_API int thesis_depth(double area, double a_min, double a_max, int min_depth, int max_depth);
// Smallest d in [min_depth, max_depth] with sqrt(area) / 2^d <= tolerance,
// else max_depth.
OCTBAKE_API int screen_depth(double area, int min_depth, int max_depth, double tolerance);
// One depth per object. `areas` are the objects' pixel areas; `max_depths`
// each object's deepest usable depth (settings.max_depth is clamped to it).
OCTBAKE_API std::vector<int> choose_depths(const LodSettings& settings, std::span<const double> areas,
                               std::span<const int> max_depths);

}  // namespace octbake
