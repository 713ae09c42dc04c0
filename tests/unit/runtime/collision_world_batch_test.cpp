// set_poses and the parallel parts of detect(): the same results as a
// set_pose loop on one thread, for every thread count and executor; refusals
// that change nothing.
#include <gtest/gtest.h>

#include <random>

#include "collision_world_util.h"

namespace octbake {
namespace {

using test::Backwards;
using test::kWork;

// 4500 objects: every parallel part (poses, cell checks, pair scan, depths)
// is split into several chunks.
constexpr int kCrowd = 4500;

TEST(CollisionWorldBatch, SetPosesAndThreadsGiveTheSetPoseLoopsResults) {
  const int frames = 2 + 2 * kWork;
  const uint64_t reference = test::crowd_hash(kCrowd, frames, 1, false);
  EXPECT_EQ(test::crowd_hash(kCrowd, frames, 1, true), reference);
  for (int threads : {2, 3, 8}) {
    EXPECT_EQ(test::crowd_hash(kCrowd, frames, threads, true), reference) << threads << " threads, set_poses";
    EXPECT_EQ(test::crowd_hash(kCrowd, frames, threads, false), reference) << threads << " threads, set_pose";
  }
  Backwards backwards;
  EXPECT_EQ(test::crowd_hash(kCrowd, frames, 1, true, &backwards), reference);
  EXPECT_GT(backwards.calls, 0);
  // The legacy areas follow the objects whose cells changed: set_poses moves
  // them into their cells itself, the loop leaves them to detect().
  const uint64_t on_cell_change =
      test::crowd_hash(kCrowd, frames, 1, false, nullptr, LodPolicy::screen, AreaRefresh::on_cell_change);
  for (int threads : {1, 2})
    EXPECT_EQ(test::crowd_hash(kCrowd, frames, threads, true, nullptr, LodPolicy::screen, AreaRefresh::on_cell_change),
              on_cell_change)
        << threads << " threads";
}

// A refused set_poses changes nothing: the next frames' contacts, stats
// (area computations, box tests) and bounds are those of a run that never
// saw it, on every thread count and executor.
TEST(CollisionWorldBatch, RefusedBatchesChangeNothing) {
  const int frames = 2 + 2 * kWork;
  const uint64_t reference = test::crowd_hash(kCrowd, frames, 1, true);
  for (int threads : {1, 2, 3}) {
    EXPECT_EQ(test::crowd_hash(kCrowd, frames, threads, true, nullptr, LodPolicy::screen, AreaRefresh::on_demand, true),
              reference)
        << threads << " threads";
  }
  Backwards backwards;
  EXPECT_EQ(
      test::crowd_hash(kCrowd, frames, 1, true, &backwards, LodPolicy::screen, AreaRefresh::on_demand, true),
      reference);
}

class SetPosesRefusal : public ::testing::Test {
 protected:
  void SetUp() override {
    std::mt19937 rng(3);
    trees_ = test::random_trees(rng, 2);
    CollisionSettings s;
    s.threads = 2;
    world_ = std::make_unique<CollisionWorld>(s);
    for (int i = 0; i < 1200; ++i) {  // over one parallel chunk
      Pose p;
      p.position = test::random_point(rng, -50, 50);
      p.scale = 0.1;
      handles_.push_back(world_->create(TreeSource::fixed(&trees_[size_t(i) % 2]), p).value());
      poses_.push_back(p);
    }
    for (Pose& p : poses_) p.position.x() += 0.5;  // every item moves
  }

  // The call is refused with `what` in the message, and nothing moved.
  void expect_refused(const std::string& what) {
    std::vector<Pose> before;
    std::vector<Aabb> boxes;
    for (const ObjectHandle& h : handles_) {
      if (!world_->alive(h)) continue;
      before.push_back(world_->pose(h).value());
      boxes.push_back(world_->bounds(h));
    }
    const Status st = world_->set_poses(handles_, poses_);
    ASSERT_FALSE(st.ok());
    EXPECT_EQ(st.error().code, ErrorCode::invalid_argument);
    EXPECT_NE(st.error().message.find(what), std::string::npos) << st.error().message;
    size_t k = 0;
    for (const ObjectHandle& h : handles_) {
      if (!world_->alive(h)) continue;
      EXPECT_EQ(world_->pose(h).value().position, before[k].position);
      EXPECT_EQ(world_->bounds(h).min, boxes[k].min);
      ++k;
    }
  }

  std::vector<ObjectTree> trees_;
  std::unique_ptr<CollisionWorld> world_;
  std::vector<ObjectHandle> handles_;
  std::vector<Pose> poses_;
};

TEST_F(SetPosesRefusal, DuplicateObjectNamesBothItems) {
  handles_[900] = handles_[17];
  expect_refused("item 900: the same object as item 17");
}

// Sorted handles skip the duplicate pass, so a duplicate must break the
// order: here only across the boundary of two parallel chunks (512 items).
TEST_F(SetPosesRefusal, DuplicateAcrossAChunkBoundary) {
  handles_[512] = handles_[511];
  expect_refused("item 512: the same object as item 511");
}

// Handles in any order are accepted (they take the duplicate pass).
TEST_F(SetPosesRefusal, ShuffledBatchMovesEveryObject) {
  std::vector<ObjectHandle> handles = handles_;
  std::vector<Pose> poses = poses_;
  std::mt19937 rng(5);
  test::shuffle_batch(handles, poses, rng);
  ASSERT_TRUE(world_->set_poses(handles, poses).ok());
  for (size_t k = 0; k < handles_.size(); ++k) EXPECT_EQ(world_->pose(handles_[k]).value().position, poses_[k].position);
  handles[1000] = handles[3];
  poses[1000].position.y() += 1;
  const Status st = world_->set_poses(handles, poses);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("item 1000: the same object as item 3"), std::string::npos) << st.error().message;
}

TEST_F(SetPosesRefusal, BadPoseNamesTheFirstBadItem) {
  poses_[1100].scale = 0;
  poses_[700].rotation.coeffs() *= 2;
  expect_refused("item 700: pose: rotation is not a unit quaternion");
}

TEST_F(SetPosesRefusal, StaleHandle) {
  ASSERT_TRUE(world_->destroy(handles_[600]).ok());
  expect_refused("item 600: handle: object was destroyed");
}

TEST_F(SetPosesRefusal, LengthsDiffer) {
  poses_.pop_back();
  expect_refused("1200 handles but 1199 poses");
}

TEST_F(SetPosesRefusal, AcceptedBatchMovesEveryObject) {
  ASSERT_TRUE(world_->set_poses(handles_, poses_).ok());
  for (size_t k = 0; k < handles_.size(); ++k) EXPECT_EQ(world_->pose(handles_[k]).value().position, poses_[k].position);
  // The empty batch and an unchanged one are accepted and change nothing.
  EXPECT_TRUE(world_->set_poses({}, {}).ok());
  EXPECT_TRUE(world_->set_poses(handles_, poses_).ok());
}

}  // namespace
}  // namespace octbake
