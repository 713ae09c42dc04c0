// Separating axis test after Akenine-Moeller, "Fast 3D Triangle-Box Overlap
// Testing" (2001): 3 box normals, the triangle normal, 9 edge x box-axis
// cross products. Written for any axis rather than the paper's hand-expanded
// forms so that zero axes (degenerate triangles) are simply skipped.
#include "occupancy.h"

#include <Eigen/Geometry>
#include <algorithm>

namespace octbake {
namespace {

// True when the projections of the triangle (already centred on the box) and
// of the box onto `axis` are disjoint. A zero axis separates nothing.
//
// Why skipping zero axes stays exact for degenerate triangles: the 13 axes are
// the facet normals of the Minkowski sum of triangle and box. For a segment
// that sum is a zonotope spanned by the 3 box axes and the segment direction,
// whose facet normals are the box normals and direction x box-axis; a point
// needs only the box normals. Both sets are among the nonzero axes here.
//
// Why rounding cannot separate a touching pair: any axis, even a badly rounded
// one, is a valid separating axis; only the projections carry rounding error,
// about 4 ulp of |axis| * |v|, and the box radius includes pad * |axis|_1,
// which callers choose far larger than that.
bool separated(const Eigen::Vector3d& axis, const Eigen::Vector3d (&v)[3], const Eigen::Vector3d& half) {
  if (axis.x() == 0 && axis.y() == 0 && axis.z() == 0) return false;
  const double p0 = axis.dot(v[0]), p1 = axis.dot(v[1]), p2 = axis.dot(v[2]);
  const double r = half.dot(axis.cwiseAbs());
  return std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r;
}

}  // namespace

bool triangle_overlaps_box(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                           const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double pad) {
  const Eigen::Vector3d centre = 0.5 * (lo + hi);
  const Eigen::Vector3d half = 0.5 * (hi - lo) + Eigen::Vector3d::Constant(pad);
  const Eigen::Vector3d v[3] = {a - centre, b - centre, c - centre};

  // Box normals first: they reject most pairs and are exact comparisons.
  for (int i = 0; i < 3; ++i) {
    if (std::min({v[0][i], v[1][i], v[2][i]}) > half[i]) return false;
    if (std::max({v[0][i], v[1][i], v[2][i]}) < -half[i]) return false;
  }
  const Eigen::Vector3d e[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
  if (separated(e[0].cross(e[1]), v, half)) return false;
  for (const Eigen::Vector3d& edge : e) {
    // edge x unit axis, written out.
    if (separated(Eigen::Vector3d(0, edge.z(), -edge.y()), v, half)) return false;
    if (separated(Eigen::Vector3d(-edge.z(), 0, edge.x()), v, half)) return false;
    if (separated(Eigen::Vector3d(edge.y(), -edge.x(), 0), v, half)) return false;
  }
  return true;
}

}  // namespace octbake
