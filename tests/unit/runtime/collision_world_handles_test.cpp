// Handles: stale, destroyed, foreign and never-issued handles are refused
// with a typed error and change nothing; bad numbers too.
#include <gtest/gtest.h>

#include <limits>

#include "collision_world_util.h"

namespace octbake {
namespace {

ObjectTree cube() {
  OctreeMasks m;
  m.bounds = {Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1)};
  m.masks.push_back({0xFF});
  return test::make_tree(std::move(m));
}

void expect_refused(const Status& s, const char* what) {
  ASSERT_FALSE(s.ok()) << what;
  EXPECT_EQ(s.error().code, ErrorCode::invalid_argument) << what;
  EXPECT_FALSE(s.error().message.empty()) << what;
}

// Every handle-taking call refuses `h` and the world stays as it was.
void expect_all_refuse(CollisionWorld& w, ObjectHandle h) {
  const size_t n = w.size();
  EXPECT_FALSE(w.alive(h));
  expect_refused(w.set_pose(h, Pose{}), "set_pose");
  expect_refused(w.destroy(h), "destroy");
  EXPECT_FALSE(w.pose(h).ok());
  EXPECT_FALSE(w.depth(h).ok());
  EXPECT_FALSE(w.area(h).ok());
  EXPECT_EQ(w.size(), n);
}

TEST(CollisionWorldHandles, DestroyedStaleForeignAndDefaultHandlesAreRefused) {
  const ObjectTree tree = cube();
  CollisionWorld w{CollisionSettings{}};
  CollisionWorld other{CollisionSettings{}};
  const ObjectHandle a = w.create(TreeSource::fixed(&tree), Pose{}).value();
  const ObjectHandle b = w.create(TreeSource::fixed(&tree), Pose{}).value();
  EXPECT_TRUE(w.alive(a) && w.alive(b));
  EXPECT_EQ(w.size(), 2u);

  expect_all_refuse(w, ObjectHandle{});  // never issued
  ASSERT_TRUE(w.destroy(a).ok());
  expect_all_refuse(w, a);  // destroyed
  // The slot is reused by the next object: the old handle still names nothing.
  const ObjectHandle c = w.create(TreeSource::fixed(&tree), Pose{}).value();
  EXPECT_EQ(c.slot, a.slot);
  EXPECT_NE(c.generation, a.generation);
  expect_all_refuse(w, a);  // stale
  EXPECT_TRUE(w.alive(c));
  // A handle of another world, even with a matching slot and generation.
  const ObjectHandle foreign = other.create(TreeSource::fixed(&tree), Pose{}).value();
  expect_all_refuse(w, foreign);
  expect_all_refuse(w, ObjectHandle{b.slot, b.generation, foreign.world});
  expect_all_refuse(w, ObjectHandle{99, 1, b.world});  // out of range
  EXPECT_TRUE(other.alive(foreign));

  // Destroyed objects never come back in contacts.
  std::vector<Contact> contacts;
  w.detect(contacts);
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_EQ(contacts[0].a, (c.slot < b.slot ? c : b));
  ASSERT_TRUE(w.destroy(b).ok());
  w.detect(contacts);
  EXPECT_TRUE(contacts.empty());
}

TEST(CollisionWorldHandles, BadNumbersAreRefused) {
  const ObjectTree tree = cube();
  CollisionWorld w{CollisionSettings{}};
  const ObjectHandle h = w.create(TreeSource::fixed(&tree), Pose{}).value();
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  std::vector<Pose> bad(5);
  bad[0].position.x() = nan;
  bad[1].position.y() = inf;
  bad[2].scale = 0;
  bad[3].scale = -1;
  bad[4].rotation = Eigen::Quaterniond(1, 1, 0, 0);  // not unit
  for (const Pose& p : bad) {
    expect_refused(w.set_pose(h, p), "set_pose");
    EXPECT_FALSE(w.create(TreeSource::fixed(&tree), p).ok());
  }
  EXPECT_EQ(w.pose(h)->position, Eigen::Vector3d::Zero());
  EXPECT_FALSE(w.create(TreeSource::fixed(nullptr), Pose{}).ok());
  LodSettings lod;
  lod.min_depth = 3, lod.max_depth = 2;
  expect_refused(w.set_lod(lod), "set_lod");
  lod.min_depth = -1, lod.max_depth = 2;
  expect_refused(w.set_lod(lod), "set_lod");
  std::vector<ObjectHandle> out;
  EXPECT_FALSE(w.ray_cast(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 1).ok());
  EXPECT_FALSE(w.ray_cast(Eigen::Vector3d(nan, 0, 0), Eigen::Vector3d::UnitX(), 1).ok());
  EXPECT_FALSE(w.ray_cast(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), -1).ok());
  // Tiny and huge directions are directions: their squares under- or overflow.
  for (double len : {1e-300, 1e-170, 1e160, 1e300}) {
    auto hit = w.ray_cast(Eigen::Vector3d(0, 0, -5), Eigen::Vector3d(0, 0, len), 10);
    ASSERT_TRUE(hit.ok()) << len << ": " << hit.error().message;
    ASSERT_TRUE(hit->has_value()) << len;
    EXPECT_NEAR((*hit)->distance, 4, 1e-6) << len;
  }
  EXPECT_FALSE(w.overlap_box({Eigen::Vector3d::Constant(1), Eigen::Vector3d::Zero()}, out).ok());
  EXPECT_FALSE(w.overlap_sphere(Eigen::Vector3d::Zero(), -1, out).ok());
  EXPECT_FALSE(w.overlap_sphere(Eigen::Vector3d::Zero(), nan, out).ok());
  EXPECT_EQ(w.size(), 1u);
}

// A finite scale whose box is past a double (4 * 1e308): the box's rotation
// turns 0 * inf into NaN. Such an object must still meet its neighbours, at
// every depth, through set_pose, set_poses and create, not be filed in one
// corner cell of the WorldTree with a NaN box.
TEST(CollisionWorldHandles, BoxPastTheLargestDoubleStillMeetsItsNeighbours) {
  OctreeMasks m;
  m.bounds = {Eigen::Vector3d::Constant(-4), Eigen::Vector3d::Constant(4)};
  m.masks.push_back({0xFF});
  const ObjectTree big = test::make_tree(std::move(m));
  const ObjectTree small = cube();
  Pose huge;
  huge.scale = 1e308;
  Pose nearby;
  nearby.position = {5, 0, 0};
  for (int depth = 0; depth <= 1; ++depth) {
    for (int how = 0; how < 3; ++how) {
      CollisionWorld w{CollisionSettings{}};
      LodSettings lod;
      lod.policy = LodPolicy::fixed, lod.min_depth = lod.max_depth = depth;
      ASSERT_TRUE(w.set_lod(lod).ok());
      const ObjectHandle a = w.create(TreeSource::fixed(&big), how == 0 ? huge : Pose{}).value();
      const ObjectHandle b = w.create(TreeSource::fixed(&small), nearby).value();
      std::vector<Contact> contacts;
      w.detect(contacts);  // committed at a normal size first, then made huge
      if (how == 1) {
        ASSERT_TRUE(w.set_pose(a, huge).ok());
      }
      if (how == 2) {
        const ObjectHandle handles[] = {a, b};
        const Pose poses[] = {huge, nearby};
        ASSERT_TRUE(w.set_poses(handles, poses).ok());
      }
      w.detect(contacts);
      ASSERT_EQ(contacts.size(), 1u) << "depth " << depth << ", way " << how;
      EXPECT_EQ(contacts[0].a, a);
      EXPECT_EQ(contacts[0].b, b);
      EXPECT_TRUE(w.depth(a).ok());
      EXPECT_TRUE(w.area(a).ok());
    }
  }
}

// A rotation accepted as unit (|q| within 1e-6 of 1) is used as q / |q|:
// Eigen's matrix of q itself scales by ~|q|^2, 2e-6 here, which moved a cube
// resting 1e-7 into another out of contact at every depth (found by a probe
// with an exact triangle oracle: 810 of 900 such pairs missed).
TEST(CollisionWorldHandles, NearlyUnitRotationsArePlacedNormalised) {
  const ObjectTree big = cube();
  OctreeMasks m;
  m.bounds = {Eigen::Vector3d::Constant(-0.05), Eigen::Vector3d::Constant(0.05)};
  m.masks.push_back({0xFF});
  const ObjectTree small = test::make_tree(std::move(m));
  const Eigen::Quaterniond q(0.5, 0.5, 0.5, 0.5);  // exactly unit: 120 degrees about (1, 1, 1)
  for (double f : {1.0, 1 + 9.9e-7, 1 - 9.9e-7}) {
    Pose pa, pb;
    pa.rotation.coeffs() = q.coeffs() * f;
    pb.rotation.coeffs() = q.coeffs() * f;
    // b's face 1e-7 inside a's +x face, in a's (rotated) frame.
    pb.position = q * Eigen::Vector3d(1 + 0.05 - 1e-7, 0.3, 0.2);
    for (int depth = 0; depth <= 1; ++depth) {
      EXPECT_TRUE(collide({&big, pa, depth}, {&small, pb, depth}).hit) << "|q| " << f << ", depth " << depth;
      EXPECT_TRUE(collide({&small, pb, depth}, {&big, pa, depth}).hit) << "|q| " << f << ", depth " << depth;
      CollisionWorld w{CollisionSettings{}};
      LodSettings lod;
      lod.policy = LodPolicy::fixed, lod.min_depth = lod.max_depth = depth;
      ASSERT_TRUE(w.set_lod(lod).ok());
      ASSERT_TRUE(w.create(TreeSource::fixed(&big), pa).ok());
      ASSERT_TRUE(w.create(TreeSource::fixed(&small), pb).ok());
      std::vector<Contact> contacts;
      w.detect(contacts);
      EXPECT_EQ(contacts.size(), 1u) << "|q| " << f << ", depth " << depth;
    }
  }
}

}  // namespace
}  // namespace octbake
