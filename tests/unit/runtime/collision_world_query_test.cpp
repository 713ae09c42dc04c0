// Ray cast and overlap queries against brute force over every object's leaf
// boxes at its current depth, at random rotations, scales 1e-4..1e4 (times 1,
// 2^600 or 2^-600, where squared lengths over- or underflow) and offsets up
// to 1e7 (times the same).
#include <gtest/gtest.h>

#include <set>

#include "collision_world_util.h"

namespace octbake {
namespace {

using test::below;
using test::kWork;
using test::uniform;

// A third of the scenes each: plain, and scaled past where |v|^2 over- or
// underflows a double (the brute force below takes stable norms for them).
constexpr int kExponents[3] = {0, 600, -600};

// A scene's scale and offset: one of kExponents, a scale 1e-4..1e4 times
// 2^that, and the origin or (1e7, -1e7, 0.5e7) times the same.
void random_placement(std::mt19937& rng, double& scale, Eigen::Vector3d& offset) {
  const double k = std::ldexp(1.0, kExponents[below(rng, 3)]);
  scale = std::pow(10.0, uniform(rng, -4, 4)) * k;
  offset = below(rng, 2) ? Eigen::Vector3d::Zero() : Eigen::Vector3d(1e7 * k, -1e7 * k, 0.5e7 * k);
}

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
  random_placement(rng, s.scale, s.offset);
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
      const Eigen::Vector3d dir = (target - origin).stableNormalized();
      const double max_t = below(rng, 4) == 0 ? (target - origin).stableNorm() * 0.8 : 1e3 * s.scale;
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
          const double dist = (local - local.cwiseMax(-b.half).cwiseMin(b.half)).stableNorm();
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

// ---- the WorldTree queries against the scan over every object ----

// A world of hundreds to thousands of objects: some outside the world box,
// some huge (in the WorldTree's overflow set), random rotations, scales
// 1e-4..1e4 and, in half the worlds, a 1e7 offset. The grid is fine enough
// (up to 64 cells per axis) that objects span several cells.
struct BigScene {
  std::unique_ptr<CollisionWorld> world;
  std::vector<ObjectHandle> handles;
  double scale = 1;
  Eigen::Vector3d offset{0, 0, 0};
  int huge = 0, outside = 0;
};

Pose random_pose(std::mt19937& rng, const BigScene& s) {
  Pose p;
  const int kind = int(below(rng, 20));
  // Mostly inside the world box (half-width 100), some beyond it.
  const double reach = kind < 3 ? 400 : 110;
  p.position = s.offset + test::random_point(rng, -reach, reach) * s.scale;
  p.rotation = test::maybe_rotation(rng);
  p.scale = s.scale * (kind == 0 ? uniform(rng, 5, 15) : uniform(rng, 0.1, 0.6));  // kind 0: huge
  return p;
}

BigScene make_big_scene(std::mt19937& rng, const std::vector<ObjectTree>& trees, int objects) {
  BigScene s;
  random_placement(rng, s.scale, s.offset);
  CollisionSettings cs;
  cs.bounds = {s.offset.array() - 100 * s.scale, s.offset.array() + 100 * s.scale};
  cs.world_depth = int(below(rng, 7));
  cs.lod.policy = LodPolicy::screen;
  cs.lod.max_depth = 4;
  cs.lod.pixel_tolerance = 20;
  cs.camera.position = s.offset + Eigen::Vector3d(0, 0, -300 * s.scale);
  cs.camera.look_at = s.offset;
  cs.camera.near_plane = 1e-3 * s.scale;
  s.world = std::make_unique<CollisionWorld>(cs);
  for (int i = 0; i < objects; ++i)
    s.handles.push_back(s.world->create(TreeSource::fixed(&trees[below(rng, uint32_t(trees.size()))]), random_pose(rng, s)).value());
  std::vector<Contact> contacts;
  s.world->detect(contacts);  // the WorldTree holds them
  // Then churn: some destroyed, some moved or created after the last commit,
  // so the queries see committed and uncommitted objects alike.
  for (int k = 0; k < objects / 20; ++k) {
    const size_t i = below(rng, uint32_t(s.handles.size()));
    if (below(rng, 2)) {
      EXPECT_TRUE(s.world->destroy(s.handles[i]).ok());
      s.handles[i] = s.world->create(TreeSource::fixed(&trees[0]), random_pose(rng, s)).value();
    } else if (s.world->alive(s.handles[i])) {
      EXPECT_TRUE(s.world->set_pose(s.handles[i], random_pose(rng, s)).ok());
    }
  }
  const Aabb& w = s.world->world_tree().bounds();
  for (const ObjectHandle h : s.handles) {
    const Aabb& b = s.world->bounds(h);
    s.outside += !((b.min.array() >= w.min.array()).all() && (b.max.array() <= w.max.array()).all());
    s.huge += s.world->world_tree().in_overflow(h.slot);
  }
  return s;
}

void expect_same(const Result<std::optional<RayHit>>& got, const Result<std::optional<RayHit>>& want, const char* what) {
  ASSERT_TRUE(got.ok() && want.ok());
  ASSERT_EQ(got->has_value(), want->has_value()) << what;
  if (!want->has_value()) return;
  const RayHit &g = **got, &w = **want;
  EXPECT_EQ(g.object, w.object) << what;
  EXPECT_EQ(g.distance, w.distance) << what;  // bit for bit
  EXPECT_EQ(g.depth, w.depth) << what;
  EXPECT_EQ(g.box.x, w.box.x) << what;
  EXPECT_EQ(g.box.y, w.box.y) << what;
  EXPECT_EQ(g.box.z, w.box.z) << what;
}

TEST(CollisionWorldQuery, WorldTreeRayCastEqualsScanOverEveryObject) {
  std::mt19937 rng(21);
  const std::vector<ObjectTree> trees = test::random_trees(rng, 4);
  uint64_t rays = 0, hits = 0, outside_rays = 0, outside_hits = 0, huge = 0, outside = 0;
  for (int trial = 0; trial < std::max(2 * kWork, 8); ++trial) {
    BigScene s = make_big_scene(rng, trees, 200 + int(below(rng, 1800)));
    huge += s.huge, outside += s.outside;
    for (int r = 0; r < 60; ++r) {
      // Origins inside the world and far outside it; targets on objects or
      // anywhere; a third of the rays unbounded, some axis-aligned.
      const bool far = below(rng, 3) == 0;
      const Eigen::Vector3d origin = s.offset + test::random_point(rng, far ? -1000 : -120, far ? 1000 : 120) * s.scale;
      Eigen::Vector3d target;
      if (below(rng, 2)) {
        const ObjectHandle h = s.handles[below(rng, uint32_t(s.handles.size()))];
        target = s.world->pose(h).value().position;
      } else {
        target = s.offset + test::random_point(rng, -300, 300) * s.scale;
      }
      Eigen::Vector3d dir = target - origin;
      if (below(rng, 8) == 0) dir[below(rng, 3)] = 0;
      if (below(rng, 8) == 0) dir = Eigen::Vector3d::Unit(below(rng, 3)) * (below(rng, 2) ? 1 : -1);
      if (dir.squaredNorm() == 0) continue;
      const double max_t = below(rng, 3) == 0 ? INFINITY : uniform(rng, 0, 2000) * s.scale;
      const auto want = s.world->ray_cast_scan(origin, dir, max_t);
      const auto got = s.world->ray_cast(origin, dir, max_t);
      expect_same(got, want, "ray");
      if (testing::Test::HasFailure()) {
        ADD_FAILURE() << "trial " << trial << " ray " << r;
        return;
      }
      const Aabb& w = s.world->world_tree().bounds();
      const bool out = !((origin.array() >= w.min.array()).all() && (origin.array() <= w.max.array()).all());
      ++rays, outside_rays += out;
      hits += want->has_value(), outside_hits += out && want->has_value();
    }
  }
  // Not vacuous: hits and misses, rays from outside the world hitting, huge
  // and outside objects present.
  EXPECT_GT(hits, rays / 5);
  EXPECT_LT(hits, rays * 9 / 10);
  EXPECT_GT(outside_hits, 10u);
  EXPECT_GT(outside_rays, outside_hits);
  EXPECT_GT(huge, 0u);
  EXPECT_GT(outside, 0u);
}

TEST(CollisionWorldQuery, WorldTreeOverlapsEqualScanOverEveryObject) {
  std::mt19937 rng(22);
  const std::vector<ObjectTree> trees = test::random_trees(rng, 4);
  uint64_t queries = 0, nonempty = 0, found = 0;
  for (int trial = 0; trial < std::max(2 * kWork, 8); ++trial) {
    BigScene s = make_big_scene(rng, trees, 200 + int(below(rng, 1800)));
    for (int q = 0; q < 40; ++q) {
      const Eigen::Vector3d c = s.offset + test::random_point(rng, -250, 250) * s.scale;
      const double r = std::pow(10.0, uniform(rng, -1, 2.3)) * s.scale;
      const Aabb box{c.array() - r * uniform(rng, 0.1, 1), c.array() + r * uniform(rng, 0.1, 1)};
      std::vector<ObjectHandle> got, want;
      ASSERT_TRUE(s.world->overlap_box(box, got).ok());
      ASSERT_TRUE(s.world->overlap_box_scan(box, want).ok());
      ASSERT_EQ(got, want) << "box, trial " << trial;
      found += got.size(), nonempty += !got.empty();
      ASSERT_TRUE(s.world->overlap_sphere(c, r, got).ok());
      ASSERT_TRUE(s.world->overlap_sphere_scan(c, r, want).ok());
      ASSERT_EQ(got, want) << "sphere, trial " << trial;
      found += got.size(), nonempty += !got.empty();
      queries += 2;
    }
  }
  EXPECT_GT(nonempty, queries / 8);
  EXPECT_LT(nonempty, queries);
  EXPECT_GT(found, 2 * nonempty);
}

// Moves that keep an object's WorldTree cells are not listed for the next
// commit (the entry stays right); moves that change them, or leave and come
// back before the commit, are. Either way the queries and detect()'s candidate
// pairs stay exact: the tree's overlaps and ray casts equal the scans', and
// the candidate pairs equal the brute-force count of overlapping world AABBs.
TEST(CollisionWorldQuery, MovesWithinTheirCellsKeepQueriesAndPairsExact) {
  std::mt19937 rng(23);
  const std::vector<ObjectTree> trees = test::random_trees(rng, 4);
  uint64_t queries = 0, found = 0, pairs = 0;
  for (int trial = 0; trial < std::max(2 * kWork, 8); ++trial) {
    BigScene s = make_big_scene(rng, trees, 200 + int(below(rng, 800)));
    std::vector<Contact> contacts;
    for (int frame = 0; frame < 4; ++frame) {
      for (const ObjectHandle& h : s.handles) {
        if (!s.world->alive(h)) continue;
        Pose p = s.world->pose(h).value();
        const Pose start = p;
        // Steps from a thousandth of the world to a tenth (so some change cells).
        p.position += test::random_point(rng, -1, 1) * s.scale * std::pow(10.0, uniform(rng, -1, 1.3));
        if (below(rng, 8) == 0) {  // away and back before the commit
          ASSERT_TRUE(s.world->set_pose(h, p).ok());
          p = start;
          p.position.x() += 1e-6 * s.scale;
        }
        ASSERT_TRUE(s.world->set_pose(h, p).ok());
      }
      for (int q = 0; q < 20; ++q) {
        const Eigen::Vector3d c = s.offset + test::random_point(rng, -120, 120) * s.scale;
        const double r = std::pow(10.0, uniform(rng, -1, 1.7)) * s.scale;
        std::vector<ObjectHandle> got, want;
        ASSERT_TRUE(s.world->overlap_box({c.array() - r, c.array() + r}, got).ok());
        ASSERT_TRUE(s.world->overlap_box_scan({c.array() - r, c.array() + r}, want).ok());
        ASSERT_EQ(got, want) << "trial " << trial << " frame " << frame;
        found += got.size(), ++queries;
        const Eigen::Vector3d origin = s.offset + test::random_point(rng, -150, 150) * s.scale;
        const Eigen::Vector3d dir = c - origin;
        if (dir.squaredNorm() == 0) continue;
        expect_same(s.world->ray_cast(origin, dir, INFINITY), s.world->ray_cast_scan(origin, dir, INFINITY), "ray");
        ASSERT_FALSE(testing::Test::HasFailure()) << "trial " << trial << " frame " << frame;
      }
      const DetectStats d = s.world->detect(contacts);
      uint64_t overlapping = 0;
      for (size_t i = 0; i < s.handles.size(); ++i)
        for (size_t j = i + 1; j < s.handles.size(); ++j)
          if (s.world->alive(s.handles[i]) && s.world->alive(s.handles[j]) &&
              overlaps(s.world->bounds(s.handles[i]), s.world->bounds(s.handles[j])))
            ++overlapping;
      ASSERT_EQ(d.candidate_pairs, overlapping) << "trial " << trial << " frame " << frame;
      pairs += overlapping;
    }
  }
  EXPECT_GT(found, queries);  // not vacuous: queries find objects, frames have pairs
  EXPECT_GT(pairs, 100u);
}

// Queries see uncommitted poses: an object moved after the last detect() is
// found where it is now, not where the WorldTree last put it.
TEST(CollisionWorldQuery, QueriesSeeUncommittedPoses) {
  OctreeMasks m;
  m.bounds = {Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1)};
  m.masks.push_back({0xFF});
  const std::vector<ObjectTree> trees{test::make_tree(std::move(m))};
  CollisionSettings cs;
  cs.world_depth = 5;
  CollisionWorld world(cs);
  Pose p;
  p.position = {-80, 0, 0};
  const ObjectHandle h = world.create(TreeSource::fixed(&trees[0]), p).value();
  std::vector<Contact> contacts;
  world.detect(contacts);
  p.position = {80, 0, 0};
  ASSERT_TRUE(world.set_pose(h, p).ok());
  const auto hit = world.ray_cast({0, 0, 0}, {1, 0, 0}, 1000);
  ASSERT_TRUE(hit.ok() && hit->has_value());
  EXPECT_EQ((*hit)->object, h);
  EXPECT_FALSE(world.ray_cast({0, 0, 0}, {-1, 0, 0}, 1000)->has_value());
  std::vector<ObjectHandle> out;
  ASSERT_TRUE(world.overlap_box({{70, -30, -30}, {90, 30, 30}}, out).ok());
  EXPECT_EQ(out, std::vector<ObjectHandle>{h});
  ASSERT_TRUE(world.overlap_sphere({-80, 0, 0}, 5, out).ok());
  EXPECT_TRUE(out.empty());
}

}  // namespace
}  // namespace octbake
