// Pixel area of a posed box (docs/interface.md section 7): its faces clipped to the
// view frustum in camera space (Sutherland-Hodgman), projected, then the area
// of the 2D convex hull (Andrew's monotone chain, shoelace formula).
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "octbake/lod.h"

namespace octbake {
namespace {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;

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

// Right-handed camera basis (right, up, forward). A look_at equal to the
// position looks down -z; an up parallel to the view direction is replaced by
// the world axis least aligned with it.
Eigen::Matrix3d camera_basis(const Camera& camera) {
  Vec3 f = camera.look_at - camera.position;
  f = f.norm() > 0 ? Vec3(f.normalized()) : Vec3(0, 0, -1);
  Vec3 up = camera.up.norm() > 0 ? Vec3(camera.up.normalized()) : Vec3(0, 1, 0);
  Vec3 r = f.cross(up);
  if (r.norm() < 1e-9) {
    int axis = 0;
    f.cwiseAbs().minCoeff(&axis);
    r = f.cross(Vec3::Unit(axis));
  }
  r.normalize();
  Eigen::Matrix3d basis;
  basis.row(0) = r;
  basis.row(1) = r.cross(f);
  basis.row(2) = f;
  return basis;
}

}  // namespace

double pixel_area(const Camera& camera, const OrientedBox& box) {
  if (camera.viewport_w <= 0 || camera.viewport_h <= 0) return 0;
  const double w = camera.viewport_w, h = camera.viewport_h, full = w * h;

  // Everything relative to the camera, subtracted first.
  const Vec3 rel = box.center - camera.position;
  const Vec3 local = box.axes.transpose() * (-rel);
  if ((local.cwiseAbs().array() <= box.half.array()).all()) return full;

  const Eigen::Matrix3d basis = camera_basis(camera);
  const Vec3 center = basis * rel;
  const Eigen::Matrix3d axes = basis * box.axes * box.half.asDiagonal();  // half-extent vectors

  // fov in (0, 180); a near plane <= 0 becomes a tiny positive one so that
  // every kept point projects finitely.
  const double fov = std::clamp(camera.fov_y_deg, 1e-9, 180 - 1e-9) * std::numbers::pi / 180;
  const double ty = std::tan(0.5 * fov), tx = ty * w / h;
  const double scale = rel.norm() + box.half.sum();
  const double near = std::max(camera.near_plane, 1e-12 * scale);
  const std::array<Eigen::Vector4d, 5> planes = {
      Eigen::Vector4d(0, 0, 1, -near), Eigen::Vector4d(-1, 0, tx, 0), Eigen::Vector4d(1, 0, tx, 0),
      Eigen::Vector4d(0, -1, ty, 0), Eigen::Vector4d(0, 1, ty, 0)};

  std::array<Vec3, 8> corner;
  for (int k = 0; k < 8; ++k)
    corner[k] = center + axes * Vec3((k & 1) ? 1 : -1, (k & 2) ? 1 : -1, (k & 4) ? 1 : -1);
  // Corner indices per face, in cyclic order.
  constexpr int kFaces[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};

  std::array<Vec2, 6 * kMaxPolygon> pts;
  int n = 0;
  for (const auto& face : kFaces) {
    Polygon poly;
    for (int k : face) poly.v[poly.n++] = corner[k];
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
  const double area = hull_area(pts.data(), n);
  return std::isfinite(area) ? std::clamp(area, 0.0, full) : 0.0;
}

}  // namespace octbake
