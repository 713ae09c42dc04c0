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
  EXPECT_FALSE(w.overlap_box({Eigen::Vector3d::Constant(1), Eigen::Vector3d::Zero()}, out).ok());
  EXPECT_FALSE(w.overlap_sphere(Eigen::Vector3d::Zero(), -1, out).ok());
  EXPECT_FALSE(w.overlap_sphere(Eigen::Vector3d::Zero(), nan, out).ok());
  EXPECT_EQ(w.size(), 1u);
}

}  // namespace
}  // namespace octbake
