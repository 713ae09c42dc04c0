// CollisionWorld over streamed trees (TreeSource::streamed + LevelCache):
// with an unlimited budget every frame equals the same world over fully
// decoded trees bit for bit; with a small budget the budget holds after every
// frame, levels are evicted, clamped objects are counted, and every contact
// the clamped depths prove is reported (a brute force at the depths used).
#include <gtest/gtest.h>

#include <memory>
#include <set>

#include "baked_test_util.h"
#include "octbake/collision_world.h"
#include "octbake/level_cache.h"
#include "seeded_random.h"

namespace octbake {
namespace {

constexpr int kTrees = 4, kObjects = 24, kDepth = 6;

struct Pack {
  std::vector<TreeToEncode> trees;
  std::vector<uint8_t> bytes;
  std::unique_ptr<BakedFile> file;
  std::vector<ObjectTree> full;  // each tree fully decoded
};

std::unique_ptr<Pack> make_pack(uint32_t seed) {
  auto p = std::make_unique<Pack>();
  std::mt19937 rng(seed);
  for (int i = 0; i < kTrees; ++i) p->trees.push_back(test::random_tree(rng, "t" + std::to_string(i), kDepth, Compression::zstd));
  p->bytes = encode_file(p->trees, "v");
  Result<BakedFile> f = BakedFile::from_bytes(p->bytes, "pack");
  EXPECT_TRUE(f.ok());
  p->file = std::make_unique<BakedFile>(std::move(f).value());
  for (int i = 0; i < kTrees; ++i) p->full.push_back(p->file->load(i, kDepth).value());
  return p;
}

CollisionSettings settings() {
  CollisionSettings s;
  s.bounds = {Eigen::Vector3d::Constant(-8), Eigen::Vector3d::Constant(8)};
  s.world_depth = 3;
  s.lod.policy = LodPolicy::screen;
  s.lod.max_depth = kDepth;
  s.lod.pixel_tolerance = 2;
  return s;
}

// The same random poses and cameras, frame by frame, for both worlds.
struct Script {
  explicit Script(uint32_t seed) : rng(seed) {}
  std::mt19937 rng;
  Pose pose() {
    Pose p;
    p.position = test::random_point(rng, -4, 4);
    p.rotation = test::random_rotation(rng);
    p.scale = test::uniform(rng, 0.5, 2.0);
    return p;
  }
  Camera camera() {
    Camera c;
    c.position = test::random_point(rng, -30, 30);
    c.look_at = test::random_point(rng, -2, 2);
    return c;
  }
};

TEST(CollisionWorldStreaming, UnlimitedBudgetEqualsFullyDecodedTrees) {
  auto pack = make_pack(11);
  LevelCache cache;  // no budget
  std::vector<TreeId> ids;
  for (int i = 0; i < kTrees; ++i) ids.push_back(cache.add(*pack->file, i).value());
  CollisionWorld streamed(settings()), fixed(settings());
  std::vector<ObjectHandle> hs, hf;
  Script script(5);
  for (int k = 0; k < kObjects; ++k) {
    const Pose p = script.pose();
    hs.push_back(streamed.create(TreeSource::streamed(&cache, ids[k % kTrees]), p).value());
    hf.push_back(fixed.create(TreeSource::fixed(&pack->full[k % kTrees]), p).value());
  }
  uint64_t contacts = 0, pairs = 0;
  std::vector<Contact> cs, cf;
  for (int frame = 0; frame < 60; ++frame) {
    const Camera c = script.camera();
    streamed.set_camera(c);
    fixed.set_camera(c);
    for (int k = 0; k < kObjects; k += 3) {
      const Pose p = script.pose();
      ASSERT_TRUE(streamed.set_pose(hs[k], p).ok());
      ASSERT_TRUE(fixed.set_pose(hf[k], p).ok());
    }
    const DetectStats ss = streamed.detect(cs), sf = fixed.detect(cf);
    ASSERT_EQ(ss.box_tests, sf.box_tests) << "frame " << frame;
    ASSERT_EQ(ss.depth_clamps, 0u);
    ASSERT_EQ(cs.size(), cf.size()) << "frame " << frame;
    for (size_t i = 0; i < cs.size(); ++i) {
      ASSERT_EQ(cs[i].a.slot, cf[i].a.slot);
      ASSERT_EQ(cs[i].b.slot, cf[i].b.slot);
      ASSERT_EQ(cs[i].depth_a, cf[i].depth_a);
      ASSERT_EQ(cs[i].depth_b, cf[i].depth_b);
      ASSERT_EQ(cs[i].box_tests, cf[i].box_tests);
    }
    contacts += cs.size();
    pairs += ss.pair_tests;
  }
  // Not vacuous: real contacts, and levels were decoded on demand.
  EXPECT_GT(contacts, 100u);
  EXPECT_GT(pairs, contacts);
  EXPECT_GT(cache.stats().decodes, 0u);
}

TEST(CollisionWorldStreaming, SmallBudgetHoldsClampsAndReportsWhatTheHeldDepthsProve) {
  auto pack = make_pack(12);
  // About a third of what the full trees need.
  uint64_t full_bytes = 0;
  for (int i = 0; i < kTrees; ++i)
    for (int d = 1; d <= kDepth; ++d) full_bytes += ObjectTree::level_bytes(pack->file->trees()[i], d);
  LevelCache cache(full_bytes / 3);
  std::vector<TreeId> ids;
  for (int i = 0; i < kTrees; ++i) ids.push_back(cache.add(*pack->file, i).value());
  CollisionWorld world(settings());
  std::vector<ObjectHandle> hs;
  std::vector<int> tree_of;
  Script script(6);
  for (int k = 0; k < kObjects; ++k) {
    hs.push_back(world.create(TreeSource::streamed(&cache, ids[k % kTrees]), script.pose()).value());
    tree_of.push_back(k % kTrees);
  }
  uint64_t clamps = 0, contacts = 0;
  std::vector<Contact> cs;
  for (int frame = 0; frame < 60; ++frame) {
    world.set_camera(script.camera());
    for (int k = 0; k < kObjects; k += 2) ASSERT_TRUE(world.set_pose(hs[k], script.pose()).ok());
    const DetectStats st = world.detect(cs);
    ASSERT_LE(cache.stats().bytes_held, cache.budget()) << "frame " << frame;
    clamps += st.depth_clamps;
    contacts += cs.size();
    // Every pair whose trees overlap at the depths used (never deeper than
    // what is held) is a contact: a brute force over all pairs, through the
    // fully decoded trees at those depths.
    std::set<std::pair<uint32_t, uint32_t>> got;
    for (const Contact& c : cs) got.insert({c.a.slot, c.b.slot});
    for (int i = 0; i < kObjects; ++i)
      for (int j = i + 1; j < kObjects; ++j) {
        const int di = world.cached_depth(hs[i]), dj = world.cached_depth(hs[j]);
        const PairTest t = collide({&pack->full[tree_of[i]], world.pose(hs[i]).value(), di},
                                   {&pack->full[tree_of[j]], world.pose(hs[j]).value(), dj});
        const bool reported = got.count({hs[i].slot, hs[j].slot}) > 0;
        // A pair outside any candidate cell is not tested; a tested one must
        // agree. A true overlap at the used depths is always a candidate.
        if (t.hit) {
          ASSERT_TRUE(reported) << "frame " << frame << " pair " << i << "," << j;
        }
      }
  }
  EXPECT_GT(cache.stats().evictions, 0u);
  EXPECT_GT(clamps, 0u);
  EXPECT_GT(contacts, 0u);
}

// A damaged level (level 4 of a depth-5 tree does not decode): detect()
// still returns the contacts proved at the depth held (3), counts one stream
// error per failing require, and keeps the decoder's error for the app.
TEST(CollisionWorldStreaming, DamagedLevelIsReportedAndTestedAtTheHeldDepth) {
  test::ForgedTree t = test::forged_from(test::full_masks(5), fb::Compression::Zstd);
  t.name = "crate";
  t.levels[4].data.assign(t.levels[4].data.size(), 0x5A);
  test::ForgedTree good = test::forged_from(test::full_masks(5), fb::Compression::Zstd);
  good.name = "barrel";
  const std::vector<uint8_t> bytes = test::forge({t, good});
  Result<BakedFile> file = BakedFile::from_bytes(bytes, "damaged.octb");
  ASSERT_TRUE(file.ok()) << file.error().message;
  LevelCache cache;
  const TreeId broken = cache.add(*file, 0).value(), fine = cache.add(*file, 1).value();
  CollisionSettings s;
  s.bounds = {Eigen::Vector3d::Constant(-4), Eigen::Vector3d::Constant(4)};
  s.lod.policy = LodPolicy::fixed;
  s.lod.max_depth = 5;
  CollisionWorld world(s);
  EXPECT_FALSE(world.last_stream_error().has_value());
  Pose p;
  const ObjectHandle a = world.create(TreeSource::streamed(&cache, broken), p).value();
  p.position = {0.5, 0.5, 0.5};
  const ObjectHandle b = world.create(TreeSource::streamed(&cache, broken), p).value();
  p.position = {0.9, 0, 0};
  const ObjectHandle c = world.create(TreeSource::streamed(&cache, fine), p).value();
  std::vector<Contact> contacts;
  for (int frame = 0; frame < 3; ++frame) {
    const DetectStats st = world.detect(contacts);
    EXPECT_EQ(st.stream_errors, 1u) << "one failing require (two objects share the broken tree), frame " << frame;
    ASSERT_TRUE(world.last_stream_error().has_value());
    const Error& e = *world.last_stream_error();
    EXPECT_EQ(e.code, ErrorCode::decompress_failed);
    EXPECT_NE(e.message.find("damaged.octb"), std::string::npos) << e.message;
    EXPECT_NE(e.message.find("crate"), std::string::npos) << e.message;
    EXPECT_NE(e.message.find("level 4"), std::string::npos) << e.message;
    // All three overlap (solid cubes): every pair is a contact, the broken
    // tree's objects tested at the held depth 3, the good one at 5.
    ASSERT_EQ(contacts.size(), 3u);
    for (const Contact& k : contacts) {
      EXPECT_EQ(k.depth_a, k.a == c ? 5 : 3);
      EXPECT_EQ(k.depth_b, k.b == c ? 5 : 3);
    }
    EXPECT_EQ(contacts[0].a, a);
    EXPECT_EQ(contacts[0].b, b);
    EXPECT_EQ(cache.held_depth(broken), 3);
    EXPECT_EQ(cache.held_depth(fine), 5);
  }
  // Moved apart: no pair, no require, no error this frame (the last one is kept).
  p.position = {3, 3, 3};
  ASSERT_TRUE(world.set_pose(c, p).ok());
  p.position = {-3, -3, -3};
  ASSERT_TRUE(world.set_pose(b, p).ok());
  EXPECT_EQ(world.detect(contacts).stream_errors, 0u);
  EXPECT_TRUE(contacts.empty());
  EXPECT_TRUE(world.last_stream_error().has_value());
}

}  // namespace
}  // namespace octbake
