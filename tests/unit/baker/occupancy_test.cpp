// triangle_overlaps_box against two independent oracles: dense sampling of
// the triangle (no false negatives) and clipping the triangle by the box's six
// planes (no false positives beyond a hair's width).
#include "occupancy.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "seeded_random.h"

namespace octbake {
namespace {

using V = Eigen::Vector3d;

using test::random_point;
using test::uniform;

struct Box {
  V lo, hi;
};

bool inside(const V& p, const Box& b) { return (p.array() >= b.lo.array()).all() && (p.array() <= b.hi.array()).all(); }

// Barycentric grid over the triangle, edges and corners included.
bool any_sample_inside(const V& a, const V& b, const V& c, const Box& box, int steps) {
  for (int i = 0; i <= steps; ++i)
    for (int j = 0; i + j <= steps; ++j) {
      const double u = double(i) / steps, v = double(j) / steps;
      if (inside(a + u * (b - a) + v * (c - a), box)) return true;
    }
  return false;
}

// Sutherland-Hodgman: the triangle clipped by the box's closed half-spaces is
// non-empty exactly when they intersect; works for segments and points too.
bool clip_nonempty(const V& a, const V& b, const V& c, const Box& box) {
  std::vector<V> poly{a, b, c}, next;
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      const double bound = side == 0 ? box.lo[axis] : box.hi[axis];
      auto dist = [&](const V& p) { return side == 0 ? p[axis] - bound : bound - p[axis]; };
      next.clear();
      for (size_t i = 0; i < poly.size(); ++i) {
        const V& p = poly[i];
        const V& q = poly[(i + 1) % poly.size()];
        const double dp = dist(p), dq = dist(q);
        if (dp >= 0) next.push_back(p);
        if ((dp >= 0) != (dq >= 0)) next.push_back(p + (q - p) * (dp / (dp - dq)));
      }
      poly.swap(next);
      if (poly.empty()) return false;
    }
  }
  return true;
}

Box grown(const Box& b, double m) { return {b.lo - V::Constant(m), b.hi + V::Constant(m)}; }

Box random_box(std::mt19937& g) {
  const V centre = random_point(g, -0.5, 0.5);
  const V half(uniform(g, 0.05, 0.6), uniform(g, 0.05, 0.6), uniform(g, 0.05, 0.6));
  return {centre - half, centre + half};
}

// Checks the test on one case against both oracles; returns the sampled hit.
bool check_case(const V& a, const V& b, const V& c, const Box& box) {
  constexpr double kHair = 1e-9;
  const bool result = triangle_overlaps_box(a, b, c, box.lo, box.hi, /*pad=*/0);
  const bool sampled = any_sample_inside(a, b, c, box, /*steps=*/24);
  if (sampled) {
    EXPECT_TRUE(result) << "false negative (sampled point inside)";
  }
  if (clip_nonempty(a, b, c, grown(box, -kHair))) {
    EXPECT_TRUE(result) << "false negative (clip)";
  }
  if (!clip_nonempty(a, b, c, grown(box, kHair))) {
    EXPECT_FALSE(result) << "false positive (clip)";
  }
  return sampled;
}

TEST(TriangleOverlapsBox, MatchesSamplingAndClippingOnRandomTriangles) {
  std::mt19937 g(1234);
  constexpr int kCases = 20000;
  int hits = 0, yes = 0;
  for (int n = 0; n < kCases; ++n) {
    const Box box = random_box(g);
    const V a = random_point(g, -1.6, 1.6), b = random_point(g, -1.6, 1.6), c = random_point(g, -1.6, 1.6);
    hits += check_case(a, b, c, box);
    yes += triangle_overlaps_box(a, b, c, box.lo, box.hi, 0);
  }
  // Not vacuous: both outcomes are common.
  EXPECT_GT(hits, kCases * 3 / 10);
  EXPECT_LT(yes, kCases * 7 / 10);
}

TEST(TriangleOverlapsBox, DegenerateTrianglesSegmentsAndPoints) {
  std::mt19937 g(99);
  constexpr int kCases = 20000;
  int hits = 0;
  for (int n = 0; n < kCases; ++n) {
    const Box box = random_box(g);
    const V a = random_point(g, -1.2, 1.2), b = random_point(g, -1.2, 1.2);
    const double t = uniform(g, -0.5, 1.5);
    switch (n % 3) {
      case 0: hits += check_case(a, b, a + t * (b - a), box); break;  // collinear, third point anywhere on the line
      case 1: hits += check_case(a, b, b, box); break;                // repeated vertex
      default: hits += check_case(a, a, a, box); break;               // a point
    }
  }
  EXPECT_GT(hits, kCases / 10);
  EXPECT_LT(hits, kCases * 9 / 10);
}

TEST(TriangleOverlapsBox, SegmentThroughBoxWithNoVertexInside) {
  const Box box{V(0, 0, 0), V(1, 1, 1)};
  // Diagonal through the box, both ends far outside.
  EXPECT_TRUE(triangle_overlaps_box(V(-5, -5, -5), V(6, 6, 6), V(6, 6, 6), box.lo, box.hi, 0));
  EXPECT_TRUE(triangle_overlaps_box(V(-5, 0.5, 0.5), V(6, 0.5, 0.5), V(0.5, 0.5, 0.5), box.lo, box.hi, 0));
  // Just grazing the box's (1, 1) edge from outside, and just missing it.
  EXPECT_TRUE(triangle_overlaps_box(V(-1, 3, 0.5), V(3, -1, 0.5), V(3, -1, 0.5), box.lo, box.hi, 0));
  EXPECT_FALSE(triangle_overlaps_box(V(-1, 3.01, 0.5), V(3.01, -1, 0.5), V(3.01, -1, 0.5), box.lo, box.hi, 0));
  // A big triangle that contains the box's centre plane but no box corner.
  EXPECT_TRUE(triangle_overlaps_box(V(-10, -10, 0.5), V(10, -10, 0.5), V(0, 10, 0.5), box.lo, box.hi, 0));
}

TEST(TriangleOverlapsBox, SeparatedByConstructedPlaneIsFalse) {
  std::mt19937 g(7);
  for (int n = 0; n < 5000; ++n) {
    const Box box = random_box(g);
    V dir = random_point(g, -1, 1);
    if (dir.norm() < 1e-3) continue;
    dir.normalize();
    // Box support along dir, then a triangle wholly beyond it by a gap.
    const V centre = 0.5 * (box.lo + box.hi), half = 0.5 * (box.hi - box.lo);
    const double box_max = dir.dot(centre) + half.dot(dir.cwiseAbs());
    V a = random_point(g, -1, 1), b = random_point(g, -1, 1), c = random_point(g, -1, 1);
    const double gap = uniform(g, 1e-6, 0.2);
    const double shift = box_max + gap - std::min({dir.dot(a), dir.dot(b), dir.dot(c)});
    a += shift * dir, b += shift * dir, c += shift * dir;
    EXPECT_FALSE(triangle_overlaps_box(a, b, c, box.lo, box.hi, 0));
    // The constructed case really is separated (the sampling oracle agrees).
    EXPECT_FALSE(any_sample_inside(a, b, c, grown(box, gap * 0.5), 8));
  }
}

TEST(TriangleOverlapsBox, PadGrowsTheBox) {
  const Box box{V(0, 0, 0), V(1, 1, 1)};
  const V a(1.1, 0.5, 0.5), b(1.2, 0.6, 0.5), c(1.2, 0.4, 0.6);
  EXPECT_FALSE(triangle_overlaps_box(a, b, c, box.lo, box.hi, 0.05));
  EXPECT_TRUE(triangle_overlaps_box(a, b, c, box.lo, box.hi, 0.11));
  // A flat box (zero thickness) is still hit by a triangle crossing its plane.
  EXPECT_TRUE(triangle_overlaps_box(V(0.5, 0.5, -1), V(0.5, 0.6, 1), V(0.6, 0.5, 1), V(0, 0, 0), V(1, 1, 0), 0));
}

}  // namespace
}  // namespace octbake
