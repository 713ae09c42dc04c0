// World on solid box trees (every mask 0xFF: the tree at any depth is exactly
// its root box), so contact frames and responses have closed-form oracles.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <set>
#include <vector>

#include "octbake/world.h"

namespace octbake {
namespace {

double unit(std::mt19937& rng) { return double(rng() >> 8) * (1.0 / 16777216.0); }
double uniform(std::mt19937& rng, double lo, double hi) { return lo + (hi - lo) * unit(rng); }

ObjectTree solid_cube(double half, int depth) {
  OctreeMasks m;
  m.bounds = {Eigen::Vector3d::Constant(-half), Eigen::Vector3d::Constant(half)};
  for (int d = 0; d < depth; ++d) m.masks.emplace_back(size_t(1) << (3 * d), uint8_t{0xFF});
  TreeInfo info;
  info.bounds = m.bounds;
  info.depth = depth;
  return ObjectTree(std::move(info), std::move(m));
}

ObjectDesc desc(const ObjectTree& tree, Eigen::Vector3d position, Eigen::Vector3d velocity) {
  ObjectDesc o;
  o.tree = &tree;
  o.pose.position = position;
  o.velocity = velocity;
  return o;
}

WorldSettings settings(Response response, double timestep = 0.1) {
  WorldSettings s;
  s.response = response;
  s.timestep = timestep;
  s.lod.policy = LodPolicy::fixed;
  s.lod.max_depth = 3;
  return s;
}

bool same_bits(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return std::memcmp(a.data(), b.data(), sizeof(double) * 3) == 0; }

// Steps until a frame reports collisions (into c) or max_frames pass; returns
// the frame that reported them.
int step_until_contact(World& world, std::vector<Collision>& c, int max_frames) {
  int f = 0;
  while (c.empty() && f < max_frames) {
    world.step(c);
    ++f;
  }
  return f - 1;
}

// A unit cube moving +x at 4/s toward a static unit cube at x = 5, y offset
// 0.1. They overlap iff |x_a - 5| <= 1 (the y, z overlaps hold throughout).
struct HeadOn {
  ObjectTree cube = solid_cube(0.5, 3);
  static constexpr double kDt = 0.1, kSpeed = 4.0, kStart = -5.0;
  static double x_a(int f) { return kStart + kSpeed * (f * kDt); }
  static bool oracle_overlap(int f) { return std::abs(x_a(f) - 5.0) <= 1.0; }
  std::vector<ObjectDesc> objects() const {
    return {desc(cube, {kStart, 0.1, 0}, {kSpeed, 0, 0}), desc(cube, {5, 0, 0}, {0, 0, 0})};
  }
};

TEST(World, ResponseNoneReportsExactlyTheOverlappingFrames) {
  HeadOn scene;
  World world(settings(Response::none, HeadOn::kDt), scene.objects());
  std::set<int> expected, got;
  for (int f = 0; f < 60; ++f) {
    // The oracle is only decisive away from exact touching.
    ASSERT_GT(std::abs(std::abs(HeadOn::x_a(f) - 5.0) - 1.0), 1e-6);
    if (HeadOn::oracle_overlap(f)) expected.insert(f);
    std::vector<Collision> c;
    const FrameStats stats = world.step(c);
    EXPECT_EQ(stats.collisions, c.size());
    for (const Collision& k : c) {
      got.insert(f);
      EXPECT_EQ(k.a, 0u);
      EXPECT_EQ(k.b, 1u);
      EXPECT_EQ(k.depth_a, 3);
      EXPECT_EQ(k.depth_b, 3);
      EXPECT_GT(k.box_tests, 0u);
      EXPECT_NEAR(k.position_a.x(), HeadOn::x_a(f), 1e-12);
      EXPECT_TRUE(same_bits(k.position_b, Eigen::Vector3d(5, 0, 0)));
    }
  }
  ASSERT_FALSE(expected.empty());
  EXPECT_EQ(got, expected);
  EXPECT_EQ(*got.begin(), 23);  // (10 - 1) / 0.4 = 22.5: first contact in frame 23
}

TEST(World, ThesisResponseReversesAndMovesByL) {
  HeadOn scene;
  World world(settings(Response::thesis, HeadOn::kDt), scene.objects());
  std::vector<Collision> c;
  const int contact = step_until_contact(world, c, /*max_frames=*/60);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_TRUE(HeadOn::oracle_overlap(contact));
  EXPECT_FALSE(HeadOn::oracle_overlap(contact - 1));
  // l = (|v_a| + |v_b|) * 1.5 * dt, along the reversed velocity, then one step.
  const double l = (HeadOn::kSpeed + 0) * 1.5 * HeadOn::kDt;
  EXPECT_EQ(world.object(0).velocity, Eigen::Vector3d(-HeadOn::kSpeed, 0, 0));
  EXPECT_NEAR(world.object(0).pose.position.x(), HeadOn::x_a(contact) - l - HeadOn::kSpeed * HeadOn::kDt, 1e-12);
  EXPECT_TRUE(same_bits(world.object(1).pose.position, Eigen::Vector3d(5, 0, 0)));
  EXPECT_TRUE(world.object(1).velocity.isZero(0));
  // It now moves away: no further contact.
  for (int k = 0; k < 20; ++k) {
    world.step(c);
    EXPECT_EQ(c.size(), 1u);
  }
}

TEST(World, ThesisResponseMovesBothMovingObjects) {
  const ObjectTree cube = solid_cube(0.5, 2);
  const double dt = 0.05;
  // Closing speed 6: gap 2.99 at frame 0, so 2.99 - 0.3 f < 0 first at f = 10.
  World world(settings(Response::thesis, dt),
              {desc(cube, {-1.99, 0, 0}, {4, 0, 0}), desc(cube, {2, 0.2, 0.3}, {-2, 0, 0})});
  std::vector<Collision> c;
  const int contact = step_until_contact(world, c, /*max_frames=*/40);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(contact, 10);
  const double l = (4 + 2) * 1.5 * dt;
  EXPECT_EQ(world.object(0).velocity, Eigen::Vector3d(-4, 0, 0));
  EXPECT_EQ(world.object(1).velocity, Eigen::Vector3d(2, 0, 0));
  EXPECT_NEAR(world.object(0).pose.position.x(), c[0].position_a.x() - l - 4 * dt, 1e-12);
  EXPECT_NEAR(world.object(1).pose.position.x(), c[0].position_b.x() + l + 2 * dt, 1e-12);
}

TEST(World, SeparateResponsePushesOutAlongLeastPenetration) {
  HeadOn scene;
  World world(settings(Response::separate, HeadOn::kDt), scene.objects());
  std::vector<Collision> c;
  const int contact = step_until_contact(world, c, /*max_frames=*/60);
  ASSERT_EQ(c.size(), 1u);
  // Penetration on x is x_a + 0.5 - 4.5 (< 0.4), less than on y (0.9) or z (1):
  // pushed back by it, then one step with the reflected velocity.
  const double push = HeadOn::x_a(contact) + 0.5 - 4.5;
  EXPECT_EQ(world.object(0).velocity, Eigen::Vector3d(-HeadOn::kSpeed, 0, 0));
  EXPECT_NEAR(world.object(0).pose.position.x(), HeadOn::x_a(contact) - push - HeadOn::kSpeed * HeadOn::kDt, 1e-6);
  EXPECT_NEAR(world.object(0).pose.position.y(), 0.1, 0);
  EXPECT_TRUE(same_bits(world.object(1).pose.position, Eigen::Vector3d(5, 0, 0)));
  for (int k = 0; k < 20; ++k) {
    world.step(c);
    EXPECT_EQ(c.size(), 1u);
  }
}

TEST(World, WorldBoxReflectsThePosition) {
  const ObjectTree cube = solid_cube(0.5, 1);
  WorldSettings s = settings(Response::none, 0.1);
  s.bounds = {{-10, -10, -10}, {10, 10, 10}};
  World world(s, {desc(cube, {9.25, 1, 2}, {5, -1, 0})});
  std::vector<Collision> c;
  // x: 9.25, 9.75, 10.25 -> out: reversed and mirrored to 9.75, then 9.25 ...
  const double expected_x[] = {9.25, 9.75, 9.75, 9.25, 8.75};
  for (int f = 0; f < 5; ++f) {
    EXPECT_NEAR(world.object(0).pose.position.x(), expected_x[f], 1e-12) << "frame " << f;
    EXPECT_NEAR(world.object(0).pose.position.y(), 1 - 0.1 * f, 1e-12) << "frame " << f;
    EXPECT_EQ(world.object(0).velocity.x(), f < 2 ? 5 : -5) << "frame " << f;
    world.step(c);
  }
  // A long run never leaves the box.
  for (int f = 0; f < 2000; ++f) {
    world.step(c);
    const Eigen::Vector3d p = world.object(0).pose.position;
    ASSERT_TRUE((p.array() >= -10).all() && (p.array() <= 10).all()) << p.transpose();
  }
}

// A dense random scene: boxes of three sizes, some rotated, a third static.
std::vector<ObjectDesc> random_scene(const std::vector<ObjectTree>& trees, uint32_t seed, int n) {
  std::mt19937 rng(seed);
  std::vector<ObjectDesc> objects;
  for (int i = 0; i < n; ++i) {
    ObjectDesc o = desc(trees[rng() % trees.size()], Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
    for (int k = 0; k < 3; ++k) o.pose.position[k] = uniform(rng, -20, 20);
    if (i % 3 != 0)
      for (int k = 0; k < 3; ++k) o.velocity[k] = uniform(rng, -6, 6);
    if (i % 4 == 0) {
      const Eigen::Vector3d axis(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, 0.1, 1));
      o.pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(uniform(rng, 0, 3), axis.normalized()));
    }
    o.pose.scale = uniform(rng, 0.5, 2.0);
    objects.push_back(o);
  }
  return objects;
}

std::vector<ObjectTree> some_trees() { return {solid_cube(0.5, 2), solid_cube(1.0, 3), solid_cube(1.5, 4)}; }

TEST(World, StaticObjectsNeverMove) {
  const std::vector<ObjectTree> trees = some_trees();
  for (Response r : {Response::thesis, Response::separate}) {
    WorldSettings s = settings(r, 1.0 / 30);
    s.bounds = {{-25, -25, -25}, {25, 25, 25}};
    const std::vector<ObjectDesc> objects = random_scene(trees, 7, 150);
    World world(s, objects);
    std::vector<Collision> c;
    for (int f = 0; f < 60; ++f) world.step(c);
    EXPECT_GT(c.size(), 50u) << "the scene must collide for the test to mean anything";
    for (size_t i = 0; i < objects.size(); ++i) {
      if (!objects[i].velocity.isZero(0)) continue;
      EXPECT_TRUE(same_bits(world.object(i).pose.position, objects[i].pose.position)) << i;
      EXPECT_TRUE(world.object(i).velocity.isZero(0)) << i;
    }
  }
}

TEST(World, StepsAreBitIdentical) {
  const std::vector<ObjectTree> trees = some_trees();
  WorldSettings s = settings(Response::separate, 1.0 / 30);
  s.bounds = {{-25, -25, -25}, {25, 25, 25}};
  s.lod.policy = LodPolicy::screen;
  s.lod.min_depth = 0;
  s.camera.position = {0, 5, -60};
  const std::vector<ObjectDesc> objects = random_scene(trees, 99, 150);
  World w1(s, objects), w2(s, objects), w3(s, random_scene(trees, 99, 150));
  std::vector<Collision> c1, c2, c3;
  for (int f = 0; f < 80; ++f) {
    const FrameStats s1 = w1.step(c1), s2 = w2.step(c2), s3 = w3.step(c3);
    ASSERT_EQ(s1.box_tests, s2.box_tests);
    ASSERT_EQ(s1.box_tests, s3.box_tests);
    ASSERT_EQ(s1.pair_tests, s2.pair_tests);
  }
  ASSERT_GT(c1.size(), 20u);
  ASSERT_EQ(c1.size(), c2.size());
  ASSERT_EQ(c1.size(), c3.size());
  for (size_t k = 0; k < c1.size(); ++k) {
    for (const auto* c : {&c2[k], &c3[k]}) {
      EXPECT_EQ(c1[k].a, c->a);
      EXPECT_EQ(c1[k].b, c->b);
      EXPECT_EQ(c1[k].depth_a, c->depth_a);
      EXPECT_EQ(c1[k].depth_b, c->depth_b);
      EXPECT_EQ(c1[k].box_tests, c->box_tests);
      EXPECT_TRUE(same_bits(c1[k].position_a, c->position_a));
      EXPECT_TRUE(same_bits(c1[k].position_b, c->position_b));
    }
  }
  for (size_t i = 0; i < w1.size(); ++i) {
    EXPECT_TRUE(same_bits(w1.object(i).pose.position, w2.object(i).pose.position));
    EXPECT_TRUE(same_bits(w1.object(i).velocity, w2.object(i).velocity));
    EXPECT_TRUE(same_bits(w1.object(i).pose.position, w3.object(i).pose.position));
    EXPECT_TRUE(same_bits(w1.object(i).velocity, w3.object(i).velocity));
    EXPECT_EQ(w1.depth(i), w3.depth(i));
  }
}

// Unrotated solid cubes are exactly their world boxes, so with no response the
// collisions of each frame are exactly the overlapping box pairs.
TEST(World, CollisionsAreExactlyTheOverlappingBoxPairs) {
  const std::vector<ObjectTree> trees = some_trees();
  WorldSettings s = settings(Response::none, 1.0 / 30);
  s.bounds = {{-25, -25, -25}, {25, 25, 25}};
  std::vector<ObjectDesc> objects = random_scene(trees, 3, 150);
  for (ObjectDesc& o : objects) o.pose.rotation = Eigen::Quaterniond::Identity();
  World world(s, objects);
  size_t total = 0;
  for (int f = 0; f < 20; ++f) {
    std::vector<Aabb> boxes;
    for (uint32_t i = 0; i < world.size(); ++i) {
      const ObjectDesc& o = world.object(i);
      boxes.push_back(world_bounds(place(o.tree->bounds(), o.pose)));
    }
    std::vector<std::pair<uint32_t, uint32_t>> expected;
    for (uint32_t a = 0; a < world.size(); ++a)
      for (uint32_t b = a + 1; b < world.size(); ++b) {
        const Aabb& ba = boxes[a];
        const Aabb& bb = boxes[b];
        const Eigen::Vector3d gap = ba.min.cwiseMax(bb.min) - ba.max.cwiseMin(bb.max);  // > 0: apart
        ASSERT_GT(std::abs(gap.maxCoeff()), 1e-6) << "touching: the oracle would be undecided";
        if (gap.maxCoeff() < 0) expected.emplace_back(a, b);
      }
    std::vector<Collision> c;
    world.step(c);
    std::vector<std::pair<uint32_t, uint32_t>> got;
    for (const Collision& k : c) got.emplace_back(k.a, k.b);
    EXPECT_EQ(got, expected) << "frame " << f;  // also: sorted, each once
    total += got.size();
  }
  EXPECT_GT(total, 40u) << "the scene must collide for the test to mean anything";
}

// A slow cube crossing unit-2 cells: its leaf range, computed here from its
// position, changes on known frames; only those re-insert and refresh its area.
TEST(World, ReinsertsAndRefreshesAreasOnlyOnLeafChange) {
  const ObjectTree cube = solid_cube(0.25, 2);
  for (bool every_frame : {false, true}) {
    WorldSettings s = settings(Response::none, 0.1);
    s.bounds = {{-8, -8, -8}, {8, 8, 8}};
    s.world_depth = 3;  // cells of 2
    s.areas_every_frame = every_frame;
    s.camera.position = {0, 0, -30};
    const double x0 = -3.013, v = 0.3;
    World world(s, {desc(cube, {x0, 0.5, 0.5}, {v, 0, 0}), desc(cube, {6.5, 6.5, 6.5}, {0, 0, 0})});
    auto range = [](double x) { return std::pair(std::floor((x - 0.25 + 8) / 2), std::floor((x + 0.25 + 8) / 2)); };
    std::vector<Collision> c;
    uint64_t expected_reinsertions = 0;
    for (int f = 0; f < 150; ++f) {
      const double x = x0 + v * (f * 0.1);
      const bool changed = f > 0 && range(x) != range(x0 + v * ((f - 1) * 0.1));
      expected_reinsertions += changed;
      const Pose pose = world.object(0).pose;  // frame f's, which the refresh sees
      const FrameStats stats = world.step(c);
      EXPECT_EQ(stats.area_refreshes, f == 0 || every_frame ? 2u : changed ? 1u : 0u) << "frame " << f;
      if (changed) {
        EXPECT_EQ(world.area(0), pixel_area(s.camera, place(cube.bounds(), pose)));
      }
      EXPECT_EQ(world.world_tree().reinsertions(), expected_reinsertions + (range(x) != range(x + v * 0.1)))
          << "frame " << f;
    }
    EXPECT_GE(expected_reinsertions, 4u);
  }
}

// ---- motion owned by the layer: spin, camera path, threads ----

ObjectTree bar(int depth) {
  OctreeMasks m;
  m.bounds = {Eigen::Vector3d(-2, -0.2, -0.2), Eigen::Vector3d(2, 0.2, 0.2)};
  for (int d = 0; d < depth; ++d) m.masks.emplace_back(size_t(1) << (3 * d), uint8_t{0xFF});
  TreeInfo info;
  info.bounds = m.bounds;
  info.depth = depth;
  return ObjectTree(std::move(info), std::move(m));
}

bool same_bits(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return std::memcmp(a.coeffs().data(), b.coeffs().data(), sizeof(double) * 4) == 0;
}

// A bar spinning about z next to a cube: the orientation is computed from
// frame 0 every frame (bit for bit), responses never change it, and every
// frame's collisions are collide() at the spun pose.
TEST(World, SpinIsFromFrameZeroAndContactsFollowIt) {
  const ObjectTree b = bar(3), cube = solid_cube(0.5, 3);
  for (Response r : {Response::none, Response::separate, Response::thesis}) {
    WorldSettings s = settings(r, 0.1);
    ObjectDesc spinner = desc(b, {0, 0, 0}, {0, 0, 0});
    spinner.angular_velocity = {0, 0, 1.3};
    spinner.pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX()));
    const Eigen::Quaterniond q0 = spinner.pose.rotation;
    World world(s, {spinner, desc(cube, {2.3, 0, 0}, {0, 0, 0})});
    std::vector<Collision> c;
    int hits = 0, frames = 120;
    for (int f = 0; f < frames; ++f) {
      const Eigen::Quaterniond expected =
          (Eigen::Quaterniond(Eigen::AngleAxisd(1.3 * (double(f) * 0.1), Eigen::Vector3d::UnitZ())) * q0).normalized();
      if (f > 0) {
        EXPECT_TRUE(same_bits(world.object(0).pose.rotation, expected)) << "frame " << f;
      }
      const PlacedTree pa{&b, world.object(0).pose, 3}, pb{&cube, world.object(1).pose, 3};
      const bool want = collide(pa, pb).hit;
      c.clear();
      world.step(c);
      EXPECT_EQ(c.size(), size_t(want)) << "frame " << f;
      hits += want;
    }
    // It sweeps through the cube twice per turn: both hit and miss frames
    // (separate pushes it out of reach after the first contacts).
    EXPECT_GT(hits, r == Response::separate ? 0 : frames / 10);
    EXPECT_LT(hits, frames * 7 / 10);
    // Spin alone is motion: the separate response pushed the spinner off its
    // spot (the cube, static, never moves).
    EXPECT_EQ(world.object(0).pose.position.isZero(0), r != Response::separate);
    EXPECT_TRUE(same_bits(world.object(1).pose.position, Eigen::Vector3d(2.3, 0, 0)));
  }
}

TEST(World, CameraPathInterpolatesPositionAndLookAt) {
  WorldSettings s = settings(Response::none);
  s.camera.fov_y_deg = 40;
  s.camera.up = {0, 0, 1};
  s.camera_path = {{10, {0, 0, -10}, {0, 0, 0}}, {20, {10, 0, -10}, {0, 5, 0}}, {40, {10, 20, -10}, {0, 5, 0}}};
  World world(s, {});
  auto at = [&](int64_t f) { return world.camera_at(f); };
  EXPECT_EQ(at(-5).position, Eigen::Vector3d(0, 0, -10));
  EXPECT_EQ(at(10).position, Eigen::Vector3d(0, 0, -10));
  EXPECT_EQ(at(15).position, Eigen::Vector3d(5, 0, -10));
  EXPECT_EQ(at(15).look_at, Eigen::Vector3d(0, 2.5, 0));
  EXPECT_EQ(at(20).position, Eigen::Vector3d(10, 0, -10));
  EXPECT_EQ(at(30).position, Eigen::Vector3d(10, 10, -10));
  EXPECT_EQ(at(30).look_at, Eigen::Vector3d(0, 5, 0));
  EXPECT_EQ(at(1000).position, Eigen::Vector3d(10, 20, -10));
  EXPECT_EQ(at(15).fov_y_deg, 40);
  EXPECT_EQ(at(15).up, Eigen::Vector3d(0, 0, 1));
}

// Depths follow the camera path every frame: each object's depth after a
// step is screen_depth over its pixel area from that frame's camera.
TEST(World, DepthsFollowTheCameraPath) {
  const ObjectTree cube = solid_cube(0.5, 6);
  WorldSettings s = settings(Response::none);
  s.lod.policy = LodPolicy::screen;
  s.lod.min_depth = 0;
  s.lod.max_depth = 6;
  s.camera_path = {{0, {0, 0, -400}, {0, 0, 0}}, {60, {0, 0, -2}, {0, 0, 0}}};
  World world(s, {desc(cube, {0, 0, 0}, {0, 0, 0}), desc(cube, {3, 0, 0}, {0.5, 0, 0})});
  std::set<int> seen;
  std::vector<Collision> c;
  for (int f = 0; f < 70; ++f) {
    std::vector<Pose> poses = {world.object(0).pose, world.object(1).pose};
    const FrameStats stats = world.step(c);
    EXPECT_EQ(stats.area_refreshes, f <= 60 ? 2u : 0u) << "frame " << f;  // a still camera refreshes nothing
    for (size_t i = 0; i < 2; ++i) {
      const double area = pixel_area(world.camera_at(f), place(cube.bounds(), poses[i]));
      EXPECT_EQ(world.area(i), area) << "frame " << f;
      EXPECT_EQ(world.depth(i), screen_depth(area, 0, 6, s.lod.pixel_tolerance)) << "frame " << f;
    }
    seen.insert(world.depth(0));
  }
  EXPECT_GE(seen.size(), 4u);
}

// A frame's parallel parts (the motion of the moving objects, every area
// when the camera moves, the pair tests): collisions, counts, every pose and
// depth bit-identical for 1, 2, 3 and 8 threads. 1,800 objects, 600 moving,
// so that the motion and the area passes run in parts.
TEST(World, ThreadCountsGiveBitIdenticalRuns) {
  const ObjectTree cube = solid_cube(0.5, 4), b = bar(4);
  std::mt19937 rng(5);
  const double half = 36;  // the density of 300 objects in a 40-wide box
  std::vector<ObjectDesc> objects;
  for (int i = 0; i < 1800; ++i) {
    ObjectDesc o = desc(i % 2 ? cube : b, {uniform(rng, -half, half), uniform(rng, -half, half), uniform(rng, -half, half)},
                        {0, 0, 0});
    if (i % 3 == 0) o.velocity = {uniform(rng, -3, 3), uniform(rng, -3, 3), uniform(rng, -3, 3)};
    if (i % 10 == 0) o.angular_velocity = {uniform(rng, -2, 2), uniform(rng, -2, 2), uniform(rng, -2, 2)};
    objects.push_back(o);
  }
  auto run = [&](int threads) {
    WorldSettings s = settings(Response::separate, 0.05);
    s.bounds = {Eigen::Vector3d::Constant(-half), Eigen::Vector3d::Constant(half)};
    s.lod.policy = LodPolicy::screen;
    s.camera_path = {{0, {0, 0, -100}, {0, 0, 0}}, {60, {70, 20, -40}, {0, 0, 0}}};
    s.threads = threads;
    World world(s, objects);
    std::vector<std::tuple<uint32_t, uint32_t, int, int, uint64_t>> log;
    std::vector<Collision> c;
    uint64_t box_tests = 0, areas = 0;
    for (int f = 0; f < 60; ++f) {
      c.clear();
      const FrameStats st = world.step(c);
      box_tests += st.box_tests, areas += st.area_refreshes;
      for (const Collision& k : c) log.emplace_back(k.a, k.b, k.depth_a, k.depth_b, k.box_tests);
    }
    std::vector<double> state;
    for (size_t i = 0; i < world.size(); ++i) {
      const Pose& p = world.object(i).pose;
      state.insert(state.end(), {p.position.x(), p.position.y(), p.position.z(), p.rotation.w(), p.rotation.x(),
                                 world.area(i), double(world.depth(i))});
    }
    return std::tuple(log, box_tests, areas, state);
  };
  const auto reference = run(1);
  EXPECT_GT(std::get<0>(reference).size(), 100u);
  EXPECT_GE(std::get<2>(reference), 1800u * 59);  // the moving camera: every area, every frame
  for (int threads : {2, 3, 8}) EXPECT_TRUE(run(threads) == reference) << threads << " threads";
}

}  // namespace
}  // namespace octbake
