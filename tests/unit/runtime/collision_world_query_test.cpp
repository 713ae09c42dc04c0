// Ray cast and overlap queries against brute force over every object's leaf
// boxes at its current depth, at random rotations, scales 1e-4..1e4 and
// offsets up to 1e7.
#include <gtest/gtest.h>

#include <set>

#include "collision_world_util.h"

namespace octbake {
namespace {

using test::below;
using test::kWork;
using test::uniform;

struct Scene {
  std::vector<ObjectTree> trees;
  std::unique_ptr<CollisionWorld> world;
  std::vector<ObjectHandle> handles;
  std::vector<const ObjectTree*> tree;
  double scale = 1;  // objects are about 20 * scale wide
  Eigen::Vector3d offset{0, 0, 0};
};

Scene make_scene(std::mt19937& rng, const std::vector<ObjectTree>& trees) {
  Scene s;
  s.scale = std::pow(10.0, uniform(rng, -4, 4));
  s.offset = below(rng, 2) ? Eigen::Vector3d::Zero() : Eigen::Vector3d(1e7, -1e7, 0.5e7);
  CollisionSettings cs;
  cs.bounds = {s.offset.array() - 100 * s.scale, s.offset.array() + 100 * s.scale};
  cs.world_depth = 2;
  cs.lod.policy = LodPolicy::screen;
  cs.lod.max_depth = 4;
  cs.lod.pixel_tolerance = 20;
  cs.camera.position = s.offset + Eigen::Vector3d(0, 0, -150 * s.scale);
  cs.camera.look_at = s.offset;
  cs.camera.near_plane = 1e-3 * s.scale;
  s.world = std::make_unique<CollisionWorld>(cs);
  for (int i = 0; i < 6; ++i) {
    Pose p;
    p.position = s.offset + test::random_point(rng, -25, 25) * s.scale;
    p.rotation = test::maybe_rotation(rng);
    p.scale = s.scale * uniform(rng, 0.5, 1.5);
    const ObjectTree* t = &trees[below(rng, uint32_t(trees.size()))];
    s.handles.push_back(s.world->create(TreeSource::fixed(t), p).value());
    s.tree.push_back(t);
  }
  return s;
}

// A point near a random occupied leaf of a random object.
Eigen::Vector3d near_leaf(std::mt19937& rng, Scene& s, double spread) {
  const size_t i = below(rng, uint32_t(s.handles.size()));
  const std::vector<OrientedBox> leaves =
      test::world_leaves(*s.tree[i], s.world->pose(s.handles[i]).value(), s.world->depth(s.handles[i]).value());
  return leaves[below(rng, uint32_t(leaves.size()))].center + test::random_point(rng, -spread, spread) * s.scale;
}

// The tolerance of a query answer in world units: rounding at the world's
// magnitude plus a millionth of the object size.
double tolerance(const Scene& s) { return 1e-10 * s.offset.cwiseAbs().maxCoeff() + 1e-6 * 20 * s.scale; }

TEST(CollisionWorldQuery, RayCastMatchesBruteForceOverLeafBoxes) {
  std::mt19937 rng(11);
  const std::vector<ObjectTree> trees = test::random_trees(rng, 4);
  uint64_t rays = 0, hits = 0;
  std::set<int> depths;
  for (int trial = 0; trial < 20 * kWork; ++trial) {
    Scene s = make_scene(rng, trees);
    const double tol = tolerance(s);
    for (int r = 0; r < 20; ++r) {
      const Eigen::Vector3d origin = s.offset + test::random_point(rng, -60, 60) * s.scale;
      const Eigen::Vector3d target = near_leaf(rng, s, 6);
      const Eigen::Vector3d dir = (target - origin).normalized();
      const double max_t = below(rng, 4) == 0 ? (target - origin).norm() * 0.8 : 1e3 * s.scale;
      // Brute force: nearest entry into any leaf (exact and inflated by tol).
      double exact = INFINITY, loose = INFINITY;
      for (size_t i = 0; i < s.handles.size(); ++i) {
        const int d = s.world->depth(s.handles[i]).value();
        depths.insert(d);
        for (const OrientedBox& b : test::world_leaves(*s.tree[i], s.world->pose(s.handles[i]).value(), d)) {
          const double t = test::ray_obb(origin, dir, b, max_t);
          if (t >= 0) exact = std::min(exact, t);
          const double tl = test::ray_obb(origin, dir, test::inflate(b, tol), max_t + tol);
          if (tl >= 0) loose = std::min(loose, tl);
        }
      }
      Result<std::optional<RayHit>> hit = s.world->ray_cast(origin, dir * uniform(rng, 0.1, 10), max_t);
      ASSERT_TRUE(hit.ok());
      ++rays;
      if (std::isfinite(exact)) {
        ASSERT_TRUE(hit->has_value()) << "missed a leaf at " << exact << ", trial " << trial;
        EXPECT_LE((*hit)->distance, exact + tol);
      }
      if (hit->has_value()) {
        ++hits;
        const RayHit& h = **hit;
        EXPECT_TRUE(std::isfinite(loose)) << "hit nothing real, trial " << trial;
        EXPECT_GE(h.distance, loose - tol);
        // The reported box is an occupied leaf of the reported object, on the ray.
        size_t i = 0;
        while (s.handles[i] != h.object) ++i;
        ASSERT_LT(i, s.handles.size());
        EXPECT_EQ(h.depth, s.world->depth(h.object).value());
        const OrientedBox b = leaf_box({s.tree[i], s.world->pose(h.object).value(), h.depth}, h.box);
        EXPECT_GE(test::ray_obb(origin, dir, test::inflate(b, tol), max_t + tol), 0.0);
      }
    }
  }
  const double rate = double(hits) / double(rays);
  EXPECT_GT(rate, 0.3);
  EXPECT_LT(rate, 0.7);
  EXPECT_GE(depths.size(), 2u);  // the LOD really varies the tested depth
}

TEST(CollisionWorldQuery, OverlapBoxAndSphereMatchBruteForceOverLeafBoxes) {
  std::mt19937 rng(12);
  const std::vector<ObjectTree> trees = test::random_trees(rng, 4);
  uint64_t box_found = 0, sphere_found = 0, queries = 0, box_nonempty = 0, sphere_nonempty = 0;
  for (int trial = 0; trial < 20 * kWork; ++trial) {
    Scene s = make_scene(rng, trees);
    const double tol = tolerance(s);
    for (int q = 0; q < 10; ++q) {
      const Eigen::Vector3d c = near_leaf(rng, s, 6);
      const double r = uniform(rng, 0.3, 5) * s.scale;
      const Aabb box{c.array() - r, c.array() + r * uniform(rng, 0.2, 2)};
      OrientedBox qbox;
      qbox.center = 0.5 * (box.min + box.max);
      qbox.half = 0.5 * (box.max - box.min);
      std::vector<ObjectHandle> got_box, got_sphere;
      ASSERT_TRUE(s.world->overlap_box(box, got_box).ok());
      ASSERT_TRUE(s.world->overlap_sphere(c, r, got_sphere).ok());
      ++queries;
      box_nonempty += !got_box.empty(), sphere_nonempty += !got_sphere.empty();
      for (size_t i = 0; i < s.handles.size(); ++i) {
        const int d = s.world->depth(s.handles[i]).value();
        bool box_exact = false, box_loose = false, sphere_exact = false, sphere_loose = false;
        for (const OrientedBox& b : test::world_leaves(*s.tree[i], s.world->pose(s.handles[i]).value(), d)) {
          const double o = test::sat_overlap(b, qbox);
          box_exact |= o >= 0, box_loose |= o >= -tol;
          const Eigen::Vector3d local = b.axes.transpose() * (c - b.center);
          const double dist = (local - local.cwiseMax(-b.half).cwiseMin(b.half)).norm();
          sphere_exact |= dist <= r, sphere_loose |= dist <= r + tol;
        }
        const bool in_box = std::count(got_box.begin(), got_box.end(), s.handles[i]) > 0;
        const bool in_sphere = std::count(got_sphere.begin(), got_sphere.end(), s.handles[i]) > 0;
        EXPECT_TRUE(!box_exact || in_box) << "missed, trial " << trial;
        EXPECT_TRUE(!in_box || box_loose) << "nothing there, trial " << trial;
        EXPECT_TRUE(!sphere_exact || in_sphere) << "missed, trial " << trial;
        EXPECT_TRUE(!in_sphere || sphere_loose) << "nothing there, trial " << trial;
        box_found += in_box, sphere_found += in_sphere;
      }
      EXPECT_TRUE(std::is_sorted(got_box.begin(), got_box.end(), [](auto a, auto b) { return a.slot < b.slot; }));
    }
  }
  // Not vacuous: a fair share of the queries find something, not all.
  const double box_rate = double(box_nonempty) / double(queries), sphere_rate = double(sphere_nonempty) / double(queries);
  EXPECT_GT(box_rate, 0.3);
  EXPECT_LT(box_rate, 0.7);
  EXPECT_GT(sphere_rate, 0.3);
  EXPECT_LT(sphere_rate, 0.7);
  std::printf("box queries finding something: %.3f, sphere: %.3f\n", box_rate, sphere_rate);
  EXPECT_GT(box_found, box_nonempty);  // some queries find several objects
}

}  // namespace
}  // namespace octbake
