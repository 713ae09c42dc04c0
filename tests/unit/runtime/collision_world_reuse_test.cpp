// Temporal coherence's reuse: a pair tested last frame on the same trees,
// poses and depths as now is answered by last frame's result (0 box
// tests), and any change to one of those is tested again; a miss whose
// objects only translated is answered while they moved less than its
// separation.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <memory>
#include <tuple>

#include "collision_world_util.h"

namespace octbake {
namespace {

// Depth `depth`, every box occupied: a solid cube of edge 2.
ObjectTree solid_cube(int depth) {
  OctreeMasks m;
  m.bounds = {Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1)};
  for (int d = 0; d < depth; ++d) m.masks.emplace_back(size_t(1) << (3 * d), uint8_t{0xFF});
  return test::make_tree(std::move(m));
}

// Only the (-x, -y, -z) octant of [-1, 1]^3 occupied, solid below it.
ObjectTree corner_cube() {
  OctreeMasks m;
  m.bounds = {Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1)};
  m.masks = {{0x01}, std::vector<uint8_t>(1, 0xFF), std::vector<uint8_t>(8, 0xFF)};
  return test::make_tree(std::move(m));
}

Pose at(double x) {
  Pose p;
  p.position = {x, 0, 0};
  return p;
}

// Every double of the estimate, as bits.
std::vector<uint64_t> bits(const ContactEstimate& e) {
  std::vector<uint64_t> out;
  const auto add = [&](const double* v, int n) {
    for (int i = 0; i < n; ++i) out.push_back(std::bit_cast<uint64_t>(v[i]));
  };
  for (const OrientedBox* b : {&e.leaf_a, &e.leaf_b}) add(b->center.data(), 3), add(b->axes.data(), 9), add(b->half.data(), 3);
  add(e.overlap.min.data(), 3), add(e.overlap.max.data(), 3), add(e.normal.data(), 3), add(&e.penetration, 1);
  return out;
}
bool same_bits(const ContactEstimate& x, const ContactEstimate& y) { return bits(x) == bits(y); }

struct Frame {
  DetectStats stats;
  std::vector<Contact> contacts;
};

class Reuse : public ::testing::TestWithParam<bool> {  // coherence
 protected:
  Reuse() : solid_(solid_cube(4)), corner_(corner_cube()) {
    CollisionSettings s;
    s.coherence = GetParam();
    s.bounds = {Eigen::Vector3d::Constant(-10), Eigen::Vector3d::Constant(10)};
    s.world_depth = 2;
    s.lod.policy = LodPolicy::fixed;
    s.lod.max_depth = 3;
    world_ = std::make_unique<CollisionWorld>(s);
  }
  Frame detect() {
    Frame f;
    f.stats = world_->detect(f.contacts);
    return f;
  }
  // Reused pairs, as expected with coherence (none without).
  uint64_t reused(uint64_t with_coherence) const { return GetParam() ? with_coherence : 0; }

  ObjectTree solid_, corner_;
  std::unique_ptr<CollisionWorld> world_;
};

TEST_P(Reuse, UnchangedPairsKeepTheirAnswerAndAnyChangeIsTestedAgain) {
  // A and B touch; C and D's root boxes overlap but their corners do not.
  const ObjectHandle a = *world_->create(TreeSource::fixed(&solid_), at(0));
  const ObjectHandle b = *world_->create(TreeSource::fixed(&solid_), at(1.5));
  const ObjectHandle c = *world_->create(TreeSource::fixed(&corner_), at(5));
  ObjectHandle d = *world_->create(TreeSource::fixed(&corner_), at(6.5));

  const Frame first = detect();
  ASSERT_EQ(first.stats.pair_tests, 2u);
  ASSERT_EQ(first.contacts.size(), 1u);
  EXPECT_EQ(first.stats.pairs_reused, 0u);
  const Contact ab = first.contacts[0];
  EXPECT_EQ(ab.a, a);
  EXPECT_EQ(ab.depth_a, 3);
  EXPECT_GT(ab.box_tests, 0u);
  EXPECT_GT(first.stats.box_tests, ab.box_tests);  // C-D was tested down to its leaves too

  // Nothing changed, or poses set to the same bits: both answered as before.
  for (int k = 0; k < 2; ++k) {
    if (k == 1) {
      ASSERT_TRUE(world_->set_pose(b, at(1.5)).ok());
    }
    const Frame f = detect();
    ASSERT_EQ(f.contacts.size(), 1u);
    EXPECT_EQ(f.stats.pairs_reused, reused(2));
    EXPECT_EQ(f.contacts[0].a, ab.a);
    EXPECT_EQ(f.contacts[0].b, ab.b);
    EXPECT_EQ(f.contacts[0].depth_b, ab.depth_b);
    EXPECT_TRUE(same_bits(f.contacts[0].estimate, ab.estimate));
    if (GetParam()) {
      EXPECT_EQ(f.contacts[0].box_tests, 0u);
      EXPECT_EQ(f.stats.box_tests, 0u);
    }
  }

  // B moves: A-B is tested again, C-D is not; back where it was, A-B is
  // tested again (last tested at the other pose) and gives the first answer.
  for (double x : {1.51, 1.5}) {
    ASSERT_TRUE(world_->set_pose(b, at(x)).ok());
    const Frame f = detect();
    ASSERT_EQ(f.contacts.size(), 1u);
    EXPECT_EQ(f.stats.pairs_reused, reused(1)) << x;
    EXPECT_GT(f.contacts[0].box_tests, 0u) << x;
    if (x == 1.5) {
      EXPECT_TRUE(same_bits(f.contacts[0].estimate, ab.estimate));
    }
  }

  // D destroyed and created again in its slot: with the same tree and pose
  // it is tested on the same inputs, so C-D is reused; with another tree it
  // is tested again.
  for (const ObjectTree* tree : {&corner_, &solid_}) {
    const uint32_t slot = d.slot;
    ASSERT_TRUE(world_->destroy(d).ok());
    d = *world_->create(TreeSource::fixed(tree), at(6.5));
    ASSERT_EQ(d.slot, slot);
    const Frame f = detect();
    EXPECT_EQ(f.stats.pairs_reused, reused(tree == &corner_ ? 2 : 1));
    ASSERT_EQ(f.contacts.size(), 1u);  // a solid D does not reach C's corner either
    if (GetParam()) {
      EXPECT_EQ(f.contacts[0].box_tests, 0u);  // A-B, unchanged since last frame
      EXPECT_EQ(f.stats.box_tests > 0, tree == &solid_);
    }
  }
  Frame f;

  // Other depths: every pair tested again, then reused.
  LodSettings lod = world_->lod();
  lod.max_depth = 2;
  ASSERT_TRUE(world_->set_lod(lod).ok());
  f = detect();
  EXPECT_EQ(f.stats.pairs_reused, 0u);
  ASSERT_EQ(f.contacts.size(), 1u);
  EXPECT_EQ(f.contacts[0].depth_a, 2);
  EXPECT_GT(f.contacts[0].box_tests, 0u);
  f = detect();
  EXPECT_EQ(f.stats.pairs_reused, reused(2));
  ASSERT_EQ(f.contacts.size(), 1u);
  EXPECT_EQ(f.contacts[0].depth_a, 2);

  // A pair apart last frame (no test to reuse) that now touches is tested.
  ASSERT_TRUE(world_->set_pose(c, at(1.5)).ok());  // inside B: A-C, B-C new
  f = detect();
  EXPECT_EQ(f.stats.pairs_reused, reused(1));  // C-D's roots are now apart; A-B kept
  EXPECT_EQ(f.contacts.size(), 3u);
}

INSTANTIATE_TEST_SUITE_P(Coherence, Reuse, ::testing::Bool(),
                         [](const auto& info) { return info.param ? "On" : "Off"; });

// A crowd that only translates, every object moving every frame (so no pose
// repeats bit for bit): with coherence, misses are answered from collide()'s
// separation while the objects have moved less than it, and the contacts are
// frame by frame those of a world without coherence, which tests every pair.
TEST(Reuse, MissesKeptBySeparationGiveTheContactsOfFullTests) {
  std::mt19937 rng(41);
  const std::vector<ObjectTree> trees = test::random_trees(rng, 5);
  CollisionWorld* worlds[2];
  std::unique_ptr<CollisionWorld> owned[2];
  for (int w = 0; w < 2; ++w) {
    CollisionSettings s;
    s.coherence = w == 1;
    s.bounds = {Eigen::Vector3d::Constant(-10), Eigen::Vector3d::Constant(10)};
    s.world_depth = 3;
    s.lod.policy = LodPolicy::fixed;
    s.lod.max_depth = 4;
    owned[w] = std::make_unique<CollisionWorld>(s);
    worlds[w] = owned[w].get();
  }
  struct Body {
    ObjectHandle h[2];
    Pose pose;
    Eigen::Vector3d velocity;
  };
  std::vector<Body> bodies(40);
  for (Body& b : bodies) {
    b.pose.position = test::random_point(rng, -4, 4);
    // Far from the origin one time in four: separations there are measured
    // from positions near 1e7.
    if (test::below(rng, 4) == 0) b.pose.position += Eigen::Vector3d(1e7, -1e7, 1e7);
    b.pose.rotation = test::maybe_rotation(rng);
    b.pose.scale = test::uniform(rng, 0.05, 0.15);
    b.velocity = test::random_point(rng, -0.02, 0.02);
    const ObjectTree* tree = &trees[test::below(rng, uint32_t(trees.size()))];
    for (int w = 0; w < 2; ++w) b.h[w] = *worlds[w]->create(TreeSource::fixed(tree), b.pose);
  }
  const auto key = [](const Contact& c) { return std::tuple(c.a.slot, c.b.slot, c.depth_a, c.depth_b); };
  uint64_t kept_apart = 0, reused = 0, contacts = 0, box_tests[2] = {0, 0};
  for (int frame = 0; frame < 20 * test::kWork; ++frame) {
    std::vector<Contact> got[2];
    for (int w = 0; w < 2; ++w) {
      const DetectStats stats = worlds[w]->detect(got[w]);
      box_tests[w] += stats.box_tests;
      if (w == 1) kept_apart += stats.pairs_kept_apart, reused += stats.pairs_reused;
    }
    ASSERT_EQ(got[0].size(), got[1].size()) << "frame " << frame;
    for (size_t i = 0; i < got[0].size(); ++i) ASSERT_EQ(key(got[0][i]), key(got[1][i])) << "frame " << frame;
    contacts += got[0].size();
    for (Body& b : bodies) {
      b.pose.position += b.velocity;
      for (int w = 0; w < 2; ++w) ASSERT_TRUE(worlds[w]->set_pose(b.h[w], b.pose).ok());
    }
  }
  EXPECT_GT(contacts, 0u);
  EXPECT_GT(kept_apart, 0u);
  EXPECT_EQ(reused, 0u);  // every pose changed every frame
  EXPECT_LT(box_tests[1], box_tests[0]);
}

// The hollow cube [-1, 1]^3 at `depth`: the leaves on its faces occupied (as
// baking its 12 triangles with surface occupancy gives; built here, as the
// runtime's tests do not link the baker).
ObjectTree cube_shell(int depth) {
  const uint32_t last = (1u << depth) - 1;
  // Does the box at level d, coordinates c, hold a leaf on a face?
  const auto on_face = [&](int d, const std::array<uint32_t, 3>& c) {
    const int shift = depth - d;
    for (uint32_t x : c)
      if (x == 0 || ((x + 1) << shift) - 1 == last) return true;
    return false;
  };
  OctreeMasks m;
  m.bounds = {Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1)};
  std::vector<std::array<uint32_t, 3>> level = {{0, 0, 0}};  // occupied boxes, in the masks' order
  for (int d = 0; d < depth; ++d) {
    std::vector<uint8_t> masks;
    std::vector<std::array<uint32_t, 3>> next;
    for (const auto& c : level) {
      uint8_t mask = 0;
      for (uint32_t j = 0; j < 8; ++j) {
        const std::array<uint32_t, 3> child = {2 * c[0] + (j & 1), 2 * c[1] + (j >> 1 & 1), 2 * c[2] + (j >> 2 & 1)};
        if (on_face(d + 1, child)) mask |= uint8_t(1u << j), next.push_back(child);
      }
      masks.push_back(mask);
    }
    m.masks.push_back(std::move(masks));
    level = std::move(next);
  }
  return test::make_tree(std::move(m));
}

// A miss whose test takes more than 128 box tests (a near miss: here a cube
// close to the inside of a hollow one) waits 128 tests before its
// separation is first asked for; a cheaper miss is asked at once. Both are
// then kept apart while they slide less than their separation.
TEST(Reuse, NearMissesAskForTheirSeparationAfterTheLongestWait) {
  const ObjectTree shell = cube_shell(5), cube = solid_cube(4);
  const std::vector<OrientedBox> leaves = test::world_leaves(shell, Pose{}, 5);
  ASSERT_EQ(leaves.size(), 32u * 32 * 32 - 30u * 30 * 30);
  for (const OrientedBox& leaf : leaves) ASSERT_GT(leaf.center.cwiseAbs().maxCoeff(), 0.9);
  // The shell's wall leaves are 1/16 thick: inner faces at x = +-0.9375.
  struct Case {
    double x;   // the small cube's centre; it is 0.5 wide
    bool near;  // its +x face 0.0075 from the wall's leaves
  } cases[] = {{0.9375 - 0.0075 - 0.25, true}, {0.0, false}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.near ? "near" : "far");
    CollisionSettings s;
    s.bounds = {Eigen::Vector3d::Constant(-4), Eigen::Vector3d::Constant(4)};
    s.world_depth = 2;
    s.lod.policy = LodPolicy::fixed;
    s.lod.max_depth = 5;
    CollisionWorld world(s);
    ASSERT_TRUE(world.create(TreeSource::fixed(&shell), Pose{}).ok());
    Pose pose = at(c.x);
    pose.position.y() = 0.01;  // its faces off the shell's box boundaries (a separation of 0 there)
    pose.scale = 0.25;
    const ObjectHandle small = *world.create(TreeSource::fixed(&cube), pose);
    int first_kept = -1, kept = 0;
    const int frames = 200;
    for (int frame = 0; frame < frames; ++frame) {
      std::vector<Contact> contacts;
      const DetectStats stats = world.detect(contacts);
      ASSERT_EQ(stats.pair_tests, 1u) << "frame " << frame;
      ASSERT_TRUE(contacts.empty()) << "frame " << frame;
      if (frame == 0) {
        EXPECT_EQ(stats.box_tests > 128, c.near) << stats.box_tests;
      }
      if (stats.pairs_kept_apart == 1 && first_kept < 0) first_kept = frame;
      kept += int(stats.pairs_kept_apart);
      pose.position.y() += 1e-4;  // along the wall: the gap is 75 steps
      ASSERT_TRUE(world.set_pose(small, pose).ok());
    }
    if (c.near) {
      // Frame 0 tests the new pair, frames 1..128 wait, 129 asks.
      EXPECT_EQ(first_kept, 130);
    } else {
      EXPECT_EQ(first_kept, 2);  // frame 1 asks
    }
    EXPECT_GE(kept, (frames - first_kept) * 9 / 10);  // an ask now and then, in between kept apart
  }
}

}  // namespace
}  // namespace octbake
