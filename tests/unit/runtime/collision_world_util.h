// Shared pieces of the CollisionWorld tests: random trees, random poses, an
// independent box-box separating axis test, and brute force over leaf boxes.
#pragma once
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "baked_test_util.h"
#include "octbake/collision_world.h"
#include "seeded_random.h"

namespace octbake::test {

#if defined(__SANITIZE_ADDRESS__) || !defined(NDEBUG)
constexpr int kWork = 1;  // sanitizer / debug builds: a tenth of the steps
#else
constexpr int kWork = 10;
#endif

inline ObjectTree make_tree(OctreeMasks m) {
  TreeInfo info;
  info.bounds = m.bounds;
  info.depth = m.depth();
  return ObjectTree(std::move(info), std::move(m));
}

// Sparse random trees, root boxes up to 20 wide.
inline std::vector<ObjectTree> random_trees(std::mt19937& rng, int count) {
  std::vector<ObjectTree> trees;
  for (int i = 0; i < count; ++i) trees.push_back(make_tree(random_masks(rng, 2 + i % 4, 0.75, 600)));
  return trees;
}

inline Eigen::Quaterniond maybe_rotation(std::mt19937& rng) {
  return below(rng, 4) == 0 ? Eigen::Quaterniond::Identity() : random_rotation(rng);
}

// Least overlap of two oriented boxes over the 15 axes (< 0: separated).
// Written independently of the library's.
inline double sat_overlap(const OrientedBox& a, const OrientedBox& b) {
  double best = INFINITY;
  const Eigen::Vector3d t = b.center - a.center;
  std::vector<Eigen::Vector3d> axes;
  for (int i = 0; i < 3; ++i) axes.push_back(a.axes.col(i)), axes.push_back(b.axes.col(i));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) axes.push_back(a.axes.col(i).cross(b.axes.col(j)));
  for (Eigen::Vector3d l : axes) {
    if (l.norm() < 1e-9) continue;
    l.normalize();
    double ra = 0, rb = 0;
    for (int k = 0; k < 3; ++k) ra += a.half[k] * std::abs(a.axes.col(k).dot(l)), rb += b.half[k] * std::abs(b.axes.col(k).dot(l));
    best = std::min(best, ra + rb - std::abs(t.dot(l)));
  }
  return best;
}

inline OrientedBox inflate(OrientedBox b, double by) {
  b.half.array() += by;
  return b;
}

// Entry distance of a ray (unit dir) into an oriented box, < 0 for a miss.
inline double ray_obb(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const OrientedBox& b, double max_t) {
  const Eigen::Vector3d lo = b.axes.transpose() * (o - b.center), ld = b.axes.transpose() * d;
  double t0 = 0, t1 = max_t;
  for (int k = 0; k < 3; ++k) {
    if (ld[k] == 0) {
      if (std::abs(lo[k]) > b.half[k]) return -1;
      continue;
    }
    double ta = (-b.half[k] - lo[k]) / ld[k], tb = (b.half[k] - lo[k]) / ld[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta), t1 = std::min(t1, tb);
    if (t0 > t1) return -1;
  }
  return t0;
}

// Every leaf box of an object at `depth`, in the world.
inline std::vector<OrientedBox> world_leaves(const ObjectTree& tree, const Pose& pose, int depth) {
  std::vector<OrientedBox> out;
  for (const BoxCoord& c : tree.masks().boxes(depth)) out.push_back(leaf_box({&tree, pose, depth}, c));
  return out;
}

}  // namespace octbake::test
