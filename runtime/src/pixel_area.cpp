// Pixel area of a posed box (docs/interface.md section 7). A box wholly
// outside one frustum plane is 0 at once. When the whole box is in front of
// the near plane (nearly always), the faces turned towards the camera (at
// most 3) are projected and their areas summed: they tile the outline, whose
// part inside the viewport is the same region as clipping in 3D, since the
// frustum's side planes project to the rectangle's edges; each face is
// clipped in 2D only when some corner falls outside the viewport. Otherwise
// the faces are clipped to the view frustum in camera space
// (Sutherland-Hodgman), projected, and their 2D convex hull (Andrew's
// monotone chain) measured (shoelace).
#include "pixel_area.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>

namespace octbake {
namespace {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;

// Squared lengths in [2^-900, 2^900] (lengths 2^-450..2^450) neither under-
// nor overflow: there the plain sums, which keep the results' bits (the areas,
// the depths and hence the logs do not move); outside, the vector is first
// scaled by a power of two (exact), out of line, so the common case stays
// short.
bool plain(double squared_norm) { return squared_norm >= 0x1p-900 && squared_norm <= 0x1p900; }

// v times 2^-e, coordinate by coordinate (exact; 2^-e itself may not be a
// double when v is subnormal).
Vec3 times_two_to_minus(const Vec3& v, int e) {
  return v.unaryExpr([e](double x) { return std::ldexp(x, -e); });
}

[[gnu::noinline, gnu::cold]] double rescaled_length(const Vec3& v) {
  const double m = v.cwiseAbs().maxCoeff();
  if (!(m > 0) || !std::isfinite(m)) return m;  // 0, inf or NaN
  const int e = std::ilogb(m);
  return std::ldexp(times_two_to_minus(v, e).norm(), e);
}

[[gnu::noinline, gnu::cold]] Vec3 rescaled_unit(const Vec3& v) {
  const double m = v.cwiseAbs().maxCoeff();
  if (!(m > 0) || !std::isfinite(m)) return Vec3::Zero();
  return times_two_to_minus(v, std::ilogb(m)).normalized();  // largest coordinate in [1, 2)
}

// |v| for any finite v (coordinates up to 2^1000 and down to subnormal ones).
double length(const Vec3& v) {
  const double n2 = v.squaredNorm();
  return plain(n2) ? std::sqrt(n2) : rescaled_length(v);
}

// v / |v|, zero for zero: as v.normalized() where |v|^2 is plain.
Vec3 unit(const Vec3& v) {
  const double n2 = v.squaredNorm();
  return plain(n2) ? Vec3(v / std::sqrt(n2)) : rescaled_unit(v);
}

// The near plane for a box at `rel` from the camera: a near plane <= 0
// becomes a tiny positive one (1e-12 of the box's distance and size) so that
// every kept point projects finitely. The length is taken only when it can
// matter: |rel| <= its L1 norm, and the margin of 2 covers their rounding.
[[gnu::always_inline]] inline double near_plane(double near, const Vec3& rel, const Vec3& half) {
  const double size = half.sum();
  if (near > 2e-12 * (rel.cwiseAbs().sum() + size)) return near;
  return std::max(near, 1e-12 * (length(rel) + size));
}

// A face (4 corners) clipped by 5 planes gains at most one vertex per plane.
constexpr int kMaxPolygon = 4 + 5;
struct Polygon {
  std::array<Vec3, kMaxPolygon> v;
  int n = 0;
};

// Keeps the part of `poly` where dot(plane.head(3), p) + plane[3] >= 0.
Polygon clip(const Polygon& poly, const Eigen::Vector4d& plane) {
  Polygon out;
  for (int i = 0; i < poly.n; ++i) {
    const Vec3& p = poly.v[i];
    const Vec3& q = poly.v[(i + 1) % poly.n];
    const double dp = plane.head<3>().dot(p) + plane[3];
    const double dq = plane.head<3>().dot(q) + plane[3];
    if (dp >= 0) out.v[out.n++] = p;
    if ((dp >= 0) != (dq >= 0)) out.v[out.n++] = p + (q - p) * (dp / (dp - dq));
  }
  return out;
}

double cross(const Vec2& o, const Vec2& a, const Vec2& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

// Area of the convex hull of pts (reordered in place).
double hull_area(Vec2* pts, int n) {
  if (n < 3) return 0;
  std::sort(pts, pts + n, [](const Vec2& a, const Vec2& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  std::array<Vec2, 2 * 6 * kMaxPolygon> hull;
  int k = 0;
  for (int i = 0; i < n; ++i) {  // lower chain
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  for (int i = n - 2, lower = k + 1; i >= 0; --i) {  // upper chain
    while (k >= lower && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  // Shoelace relative to the first vertex: tiny far-away hulls keep their digits.
  double twice = 0;
  for (int i = 1; i + 2 < k; ++i) twice += cross(hull[0], hull[i], hull[i + 1]);
  return 0.5 * std::abs(twice);
}

// Polygon area (shoelace) relative to its first vertex: tiny far-away hulls
// keep their digits.
double polygon_area(const Vec2* v, int n) {
  double twice = 0;
  for (int i = 1; i + 1 < n; ++i) twice += cross(v[0], v[i], v[i + 1]);
  return 0.5 * std::abs(twice);
}

// Keeps the part of a convex 2D polygon with sign * p[axis] <= limit.
int clip_2d(const Vec2* in, int n, Vec2* out, int axis, double sign, double limit) {
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const Vec2& p = in[i];
    const Vec2& q = in[i + 1 == n ? 0 : i + 1];
    const double dp = limit - sign * p[axis], dq = limit - sign * q[axis];
    if (dp >= 0) out[m++] = p;
    if ((dp >= 0) != (dq >= 0)) out[m++] = p + (q - p) * (dp / (dp - dq));
  }
  return m;
}

// The box in camera space: corners (right, up, forward) and its near plane.
struct CameraSpaceBox {
  std::array<Vec3, 8> corner;
  Vec3 facing;  // per box axis u: dot(u, centre), centre relative to the camera
  Vec3 half;
  double near = 0;
};

// Corner indices per face, in cyclic order: -x, +x, -y, +y, -z, +z.
constexpr int kFaces[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};

// Whole box in front of the near plane: the faces turned towards the camera
// (at most 3) project onto the outline without overlapping, so its area is
// the sum of theirs (each a convex quad), clipped to the viewport only when
// some corner falls outside it. No hull, no sort.
double projected_area(const CameraView& v, const CameraSpaceBox& b) {
  std::array<Vec2, 8> pts;
  const double sx = 0.5 * v.width() / v.tan_x(), sy = 0.5 * v.height() / v.tan_y();
  const double hw = 0.5 * v.width(), hh = 0.5 * v.height();
  bool inside = true;
  for (int k = 0; k < 8; ++k) {
    const Vec3& p = b.corner[k];
    const double inv_z = 1 / p.z();
    pts[k] = Vec2(p.x() * inv_z * sx, p.y() * inv_z * sy);
    inside &= std::abs(pts[k].x()) <= hw && std::abs(pts[k].y()) <= hh;
  }
  double area = 0;
  for (int axis = 0; axis < 3; ++axis) {
    // Face -axis faces the camera (at the origin) iff the camera lies beyond
    // it: dot(u, centre) > h; face +axis iff dot(u, centre) < -h.
    const double s = b.facing[axis];
    if (!(std::abs(s) > b.half[axis])) continue;  // camera between the two planes: both edge-on or away
    const int* face = kFaces[2 * axis + (s < 0 ? 1 : 0)];
    std::array<Vec2, 4 + 4> quad, other;
    for (int k = 0; k < 4; ++k) quad[k] = pts[face[k]];
    int n = 4;
    if (!inside) {
      n = clip_2d(quad.data(), n, other.data(), 0, +1, hw);
      n = clip_2d(other.data(), n, quad.data(), 0, -1, hw);
      n = clip_2d(quad.data(), n, other.data(), 1, +1, hh);
      n = clip_2d(other.data(), n, quad.data(), 1, -1, hh);
    }
    if (n >= 3) area += polygon_area(quad.data(), n);
  }
  return area;
}

// Some corner behind the near plane: clip the faces in 3D first.
double clipped_area(const CameraView& v, const CameraSpaceBox& b) {
  const double tx = v.tan_x(), ty = v.tan_y(), w = v.width(), h = v.height();
  const std::array<Eigen::Vector4d, 5> planes = {
      Eigen::Vector4d(0, 0, 1, -b.near), Eigen::Vector4d(-1, 0, tx, 0), Eigen::Vector4d(1, 0, tx, 0),
      Eigen::Vector4d(0, -1, ty, 0), Eigen::Vector4d(0, 1, ty, 0)};
  std::array<Vec2, 6 * kMaxPolygon> pts;
  int n = 0;
  for (const auto& face : kFaces) {
    Polygon poly;
    for (int k : face) poly.v[poly.n++] = b.corner[k];
    for (const auto& plane : planes) poly = clip(poly, plane);
    for (int i = 0; i < poly.n; ++i) {
      const Vec3& p = poly.v[i];
      // Pixels from the viewport centre (no +1 offset, which would round away
      // the size of a distant box).
      const double x = std::clamp(p.x() / (p.z() * tx) * 0.5 * w, -0.5 * w, 0.5 * w);
      const double y = std::clamp(p.y() / (p.z() * ty) * 0.5 * h, -0.5 * h, 0.5 * h);
      pts[n++] = Vec2(x, y);
    }
  }
  return hull_area(pts.data(), n);
}

enum class Where { encloses_camera, outside, in_front, straddling };

Where to_camera_space(const CameraView& v, const OrientedBox& box, CameraSpaceBox& b) {
  const Camera& camera = v.camera();
  const Vec3 rel = box.center - camera.position;
  const Vec3 local = box.axes.transpose() * (-rel);
  if ((local.cwiseAbs().array() <= box.half.array()).all()) return Where::encloses_camera;

  const Eigen::Matrix3d& basis = v.basis();
  const Vec3 center = basis * rel;
  const Eigen::Matrix3d axes = basis * box.axes * box.half.asDiagonal();  // half-extent vectors
  b.near = near_plane(camera.near_plane, rel, box.half);
  const Vec3 a0 = axes.col(0), a1 = axes.col(1), a2 = axes.col(2);
  b.facing = -local;
  b.half = box.half;
  for (int k = 0; k < 8; ++k)
    b.corner[k] = center + ((k & 1) ? a0 : Vec3(-a0)) + ((k & 2) ? a1 : Vec3(-a1)) + ((k & 4) ? a2 : Vec3(-a2));
  // Wholly outside one plane of the frustum: nothing of it is in view.
  const double tx = v.tan_x(), ty = v.tan_y();
  uint32_t out_near = 0, out_left = 0, out_right = 0, out_down = 0, out_up = 0;
  for (int k = 0; k < 8; ++k) {
    const Vec3& p = b.corner[k];
    out_near += p.z() - b.near < 0;
    out_left += tx * p.z() + p.x() < 0;
    out_right += tx * p.z() - p.x() < 0;
    out_down += ty * p.z() + p.y() < 0;
    out_up += ty * p.z() - p.y() < 0;
  }
  if (out_near == 8 || out_left == 8 || out_right == 8 || out_down == 8 || out_up == 8) return Where::outside;
  return out_near == 0 ? Where::in_front : Where::straddling;
}

double finite_area(double area, double full) { return std::isfinite(area) ? std::clamp(area, 0.0, full) : 0.0; }

}  // namespace

// Right-handed camera basis (right, up, forward). A look_at equal to the
// position looks down -z; an up parallel to the view direction is replaced by
// the world axis least aligned with it.
CameraView::CameraView(const Camera& camera) : camera_(camera) {
  // Directions of any finite length (a camera 2^1000 from its target, or
  // 2^-1000) are still directions.
  Vec3 f = unit(camera.look_at - camera.position);
  if (f.isZero(0)) f = Vec3(0, 0, -1);
  Vec3 up = unit(camera.up);
  if (up.isZero(0)) up = Vec3(0, 1, 0);
  Vec3 r = f.cross(up);
  if (r.norm() < 1e-9) {
    int axis = 0;
    f.cwiseAbs().minCoeff(&axis);
    r = f.cross(Vec3::Unit(axis));
  }
  r.normalize();
  basis_.row(0) = r;
  basis_.row(1) = r.cross(f);
  basis_.row(2) = f;
  // fov in (0, 180).
  const double fov = std::clamp(camera.fov_y_deg, 1e-9, 180 - 1e-9) * std::numbers::pi / 180;
  width_ = camera.viewport_w, height_ = camera.viewport_h;
  tan_y_ = std::tan(0.5 * fov);
  tan_x_ = tan_y_ * width_ / height_;
}

double pixel_area(const CameraView& view, const OrientedBox& box) {
  if (view.width() <= 0 || view.height() <= 0) return 0;
  const double full = view.width() * view.height();
  CameraSpaceBox b;
  switch (to_camera_space(view, box, b)) {
    case Where::encloses_camera: return full;
    case Where::outside: return 0;
    case Where::in_front: return finite_area(projected_area(view, b), full);
    case Where::straddling: return finite_area(clipped_area(view, b), full);
  }
  return 0;
}

double pixel_area(const Camera& camera, const OrientedBox& box) { return pixel_area(CameraView(camera), box); }

double pixel_area_lower_bound(const CameraView& view, const OrientedBox& box) {
  if (view.width() <= 0 || view.height() <= 0) return 0;
  const Camera& camera = view.camera();
  const Vec3 rel = box.center - camera.position;
  const Vec3 c = view.basis() * rel;
  const double r = box.half.minCoeff();
  // pixel_area's near plane; the sphere must lie in front of it and inside
  // the four side planes (tan * z +- x >= 0), by its radius.
  const double near = near_plane(camera.near_plane, rel, box.half);
  const double tx = view.tan_x(), ty = view.tan_y();
  const double rx = r * std::sqrt(1 + tx * tx), ry = r * std::sqrt(1 + ty * ty);
  if (!(r > 0) || c.z() - r < near || tx * c.z() + c.x() < rx || tx * c.z() - c.x() < rx || ty * c.z() + c.y() < ry ||
      ty * c.z() - c.y() < ry)
    return 0;
  // Solid angle of the sphere, 2 pi (1 - cos a) with sin a = r / |c| (written
  // without cancellation), in pixels: the image plane at z = 1 is scaled by
  // w / (2 tan_x) and h / (2 tan_y).
  const double c2 = c.squaredNorm();
  double s2;
  if (plain(c2)) {
    s2 = r * r / c2;
  } else {  // (r / |c|)^2, the same to rounding
    const double sin_a = r / rescaled_length(c);
    s2 = sin_a * sin_a;
  }
  const double solid = 2 * std::numbers::pi * s2 / (1 + std::sqrt(1 - s2));
  const double pixels = solid * (0.5 * view.width() / tx) * (0.5 * view.height() / ty);
  // Rounding of both computations is ~1e-15 relative: a wide margin.
  return std::isfinite(pixels) ? std::min(pixels * (1 - 1e-9), view.width() * view.height()) : 0.0;
}

double pixel_area_upper_bound(const CameraView& view, const OrientedBox& box) {
  if (view.width() <= 0 || view.height() <= 0) return 0;
  const double full = view.width() * view.height();
  const Camera& camera = view.camera();
  const Vec3 rel = box.center - camera.position;
  const Vec3 c = view.basis() * rel;
  // A sphere holding the box: radius the L1 norm of the half extents (>= the
  // half diagonal, and no squares to under- or overflow). Margins of 1e-9 of
  // the magnitudes cover the rounding of pixel_area's corners.
  const double r = box.half.cwiseAbs().sum();
  const double margin = 1e-9 * (c.cwiseAbs().sum() + r);
  const double near = near_plane(camera.near_plane, rel, box.half);
  const double tx = view.tan_x(), ty = view.tan_y();
  const double rx = r * std::sqrt(1 + tx * tx) + margin, ry = r * std::sqrt(1 + ty * ty) + margin;
  // The cube around the sphere holds the camera: the box may enclose it
  // (pixel_area: the whole viewport), even wholly behind a near plane.
  if (c.cwiseAbs().maxCoeff() <= r + margin) return full;
  // Wholly outside one plane of the view frustum, as then is every corner:
  // pixel_area is 0.
  if (c.z() + r + margin < near || tx * c.z() + c.x() < -rx || tx * c.z() - c.x() < -rx ||
      ty * c.z() + c.y() < -ry || ty * c.z() - c.y() < -ry)
    return 0;
  if (!(c.z() - r - margin > near)) return full;  // reaches the near plane
  // The box's image lies in that of the cube [c - r, c + r], at z >= zl > 0,
  // where x / z and y / z are monotone in each coordinate: their extremes are
  // at the cube's corners. That rectangle, clipped to the viewport
  // (|x / z| <= tan_x, |y / z| <= tan_y), in pixels.
  const double zl = c.z() - r, zh = c.z() + r;
  const auto range = [&](double lo, double hi, double tan) {
    const double a = std::max(std::min(lo / zl, lo / zh), -tan), b = std::min(std::max(hi / zl, hi / zh), tan);
    return std::max(b - a, 0.0);
  };
  const double pixels =
      range(c.x() - r, c.x() + r, tx) * (0.5 * view.width() / tx) * range(c.y() - r, c.y() + r, ty) *
      (0.5 * view.height() / ty);
  return std::isfinite(pixels) ? std::min(pixels * (1 + 1e-9) + 1e-12 * full, full) : full;
}

namespace detail {
double pixel_area_clipped(const Camera& camera, const OrientedBox& box) {
  const CameraView view(camera);
  if (view.width() <= 0 || view.height() <= 0) return 0;
  const double full = view.width() * view.height();
  CameraSpaceBox b;
  const Where where = to_camera_space(view, box, b);
  return where == Where::encloses_camera ? full : finite_area(clipped_area(view, b), full);
}
}  // namespace detail

}  // namespace octbake
