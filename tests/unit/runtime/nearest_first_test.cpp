// collide's nearest-first order of a split box's children (nearest_first.h)
// against the children's distances, computed one by one.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <bit>
#include <cmath>
#include <random>
#include <vector>

#include "nearest_first.h"
#include "seeded_random.h"

namespace octbake {
namespace {

using test::random_rotation;
using test::uniform;
using test::uniform01;

// The octants nearest_first visits for `hits`, in visiting order.
std::vector<int> visits(const double (&w)[3], uint32_t hits) {
  uint32_t order = 0, left = 0;
  nearest_first(w, hits, order, left);
  std::vector<int> out;
  for (; left != 0; left &= left - 1) out.push_back(int((order >> (3 * std::countr_zero(left))) & 7u));
  return out;
}

// Child j's centre relative to the other box's centre p: p + sum_k s_k u_k,
// s_k = +1 where bit k of j is set. Its squared length, in long double.
long double distance2(const Eigen::Vector3d& p, const Eigen::Vector3d (&u)[3], int j) {
  long double d2 = 0;
  for (int m = 0; m < 3; ++m) {
    long double c = p[m];
    for (int k = 0; k < 3; ++k) c += ((j >> k) & 1 ? 1.0L : -1.0L) * u[k][m];
    d2 += c * c;
  }
  return d2;
}

// Every hit mask: each overlapping child is visited once, and no other, for
// weights with ties (equal, zero, a + b = c) and without.
TEST(NearestFirst, VisitsEachHitOnce) {
  std::mt19937 rng(11);
  std::vector<std::array<double, 3>> weights = {{0, 0, 0},    {1, 1, 1},     {-1, 1, -1}, {1, 2, 3},
                                                {-3, 2, -1},  {2, -1, 1},    {0, -0.0, 5}, {1e-300, -1e300, 0}};
  for (int i = 0; i < 200; ++i) weights.push_back({uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)});
  for (const auto& wa : weights) {
    const double w[3] = {wa[0], wa[1], wa[2]};
    for (uint32_t hits = 1; hits < 256; ++hits) {
      const std::vector<int> v = visits(w, hits);
      ASSERT_EQ(v.size(), size_t(std::popcount(hits)));
      uint32_t seen = 0;
      for (int j : v) {
        ASSERT_TRUE(hits & (1u << j)) << "octant " << j << " is not a hit";
        ASSERT_FALSE(seen & (1u << j)) << "octant " << j << " twice";
        seen |= 1u << j;
      }
    }
  }
}

// Random placements, as the descent sees them (B's box rotated, sizes 1e-4
// to 1e4 apart per axis, flat boxes, the other box's centre near or far):
// the 8 children come in order of their distance to the other box's centre,
// up to rounding, and so does every subset of them.
TEST(NearestFirst, OrderFollowsTheChildrensDistances) {
  std::mt19937 rng(12);
  for (int run = 0; run < 20000; ++run) {
    const Eigen::Matrix3d r = random_rotation(rng).toRotationMatrix();
    Eigen::Vector3d q;
    for (int k = 0; k < 3; ++k) q[k] = std::pow(10.0, uniform(rng, -4, 4));
    if (run % 7 == 0) q[run % 3] = 0;  // a flat box
    const bool rotated = run % 2 == 1;  // B's steps (rotated) or A's (its axes)
    Eigen::Vector3d u[3];
    for (int k = 0; k < 3; ++k)
      u[k] = rotated ? Eigen::Vector3d(q[k] * r.col(k)) : Eigen::Vector3d(-q[k] * Eigen::Vector3d::Unit(k));
    const double reach = q.maxCoeff() * std::pow(10.0, uniform(rng, -3, 3));
    const Eigen::Vector3d p(uniform(rng, -reach, reach), uniform(rng, -reach, reach), uniform(rng, -reach, reach));
    double w[3];
    for (int k = 0; k < 3; ++k) w[k] = (p[0] * u[k][0] + p[1] * u[k][1]) + p[2] * u[k][2];
    // Rounding: ~1e-16 of the terms, and the u_k orthogonal only to ~1e-16.
    const long double tol = 1e-12L * (p.squaredNorm() + 3 * q.squaredNorm());
    const uint32_t hits = run % 5 == 0 ? 0xffu : 1u + uint32_t(uniform01(rng) * 255);
    const std::vector<int> v = visits(w, hits);
    for (size_t i = 1; i < v.size(); ++i)
      ASSERT_LE(distance2(p, u, v[i - 1]), distance2(p, u, v[i]) + tol)
          << "run " << run << ": octant " << v[i - 1] << " before the nearer " << v[i];
  }
}

}  // namespace
}  // namespace octbake
