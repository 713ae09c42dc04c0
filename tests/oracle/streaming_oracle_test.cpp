// Streamed levels against the exact answer (FCL): real meshes baked into one
// pack, levels decoded on demand by a LevelCache as a screen-space LOD asks
// for them. With a small budget the budget holds, levels are evicted and
// re-decoded, and still no contact is missed; with an unlimited budget every
// pair test equals the fully loaded one bit for bit.
#include <fcl/fcl.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <random>

#include "build_tree.h"
#include "import.h"
#include "octbake/collide.h"
#include "octbake/level_cache.h"
#include "octbake/lod.h"
#include "seeded_random.h"

namespace octbake {
namespace {

constexpr int kDepth = 6;

int pose_count(int release_count) {
#if defined(__SANITIZE_ADDRESS__) || !defined(NDEBUG)
  release_count /= 10;
#endif
  return std::max(release_count, 1);
}

struct Model {
  Mesh mesh;
  Eigen::Vector3d centre;
  double radius = 1;
  std::shared_ptr<fcl::CollisionGeometryd> fcl;  // scaled to radius 1, as posed below
};

// The bundled assets baked to depth 6 into one pack, plus their FCL models.
struct Scene {
  std::vector<Model> models;
  std::vector<uint8_t> pack;
};

const Scene& scene() {
  static const Scene s = [] {
    Scene out;
    std::vector<std::string> paths;
    for (const auto& e : std::filesystem::directory_iterator(std::filesystem::path(OCTBAKE_SOURCE_DIR) / "assets"))
      if (e.path().extension() == ".obj") paths.push_back(e.path().string());
    std::sort(paths.begin(), paths.end());
    paths.push_back("/usr/share/assimp/models/OBJ/spider.obj");
    std::vector<TreeToEncode> trees;
    for (const std::string& path : paths) {
      Result<Mesh> mesh = import_mesh(path);
      if (!mesh) {
        ADD_FAILURE() << path << ": " << mesh.error().message;
        continue;
      }
      TreeToEncode t;
      t.name = std::filesystem::path(path).stem().string();
      t.options.depth = kDepth;
      t.masks = build_tree(*mesh, kDepth, Occupancy::surface);
      Model m;
      m.centre = 0.5 * (t.masks.bounds.min + t.masks.bounds.max);
      m.radius = 0.5 * (t.masks.bounds.max - t.masks.bounds.min).norm();
      auto bvh = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
      std::vector<fcl::Vector3d> points;
      for (const auto& p : mesh->positions) points.push_back(p / m.radius);
      std::vector<fcl::Triangle> tris;
      for (const auto& tri : mesh->triangles) tris.emplace_back(tri[0], tri[1], tri[2]);
      bvh->beginModel();
      bvh->addSubModel(points, tris);
      bvh->endModel();
      m.fcl = bvh;
      m.mesh = std::move(mesh).value();
      out.models.push_back(std::move(m));
      trees.push_back(std::move(t));
    }
    out.pack = encode_file(trees, "streaming-oracle");
    return out;
  }();
  return s;
}

fcl::Transform3d to_fcl(const Pose& pose) {
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.linear() = pose.rotation.toRotationMatrix();
  tf.translation() = pose.position;
  return tf;
}

struct Frame {
  size_t a = 0, b = 0;
  Pose pa, pb;
  int da = 0, db = 0;  // what the LOD asks for
};

// A random pair, bounds centres up to 2.2 radii apart (radius 1 each), seen
// from a random camera; each object's depth is the screen LOD of its box.
Frame random_frame(std::mt19937& rng, const Scene& s) {
  Frame f;
  f.a = rng() % s.models.size();
  f.b = rng() % s.models.size();
  const Model &ma = s.models[f.a], &mb = s.models[f.b];
  const Eigen::Vector3d dir = test::random_rotation(rng) * Eigen::Vector3d::UnitX();
  const double distance = 2.2 * test::uniform01(rng);
  f.pa.rotation = test::random_rotation(rng);
  f.pb.rotation = test::random_rotation(rng);
  f.pa.scale = 1 / ma.radius;
  f.pb.scale = 1 / mb.radius;
  f.pa.position = -(f.pa.rotation * (f.pa.scale * ma.centre));
  f.pb.position = distance * dir - f.pb.rotation * (f.pb.scale * mb.centre);
  Camera camera;
  camera.viewport_w = 640;
  camera.viewport_h = 480;
  camera.position = (3 + 60 * test::uniform01(rng)) * (test::random_rotation(rng) * Eigen::Vector3d::UnitZ());
  const auto depth = [&](const Pose& pose, const Model& m) {
    const Aabb local{m.centre - Eigen::Vector3d::Constant(m.radius), m.centre + Eigen::Vector3d::Constant(m.radius)};
    return screen_depth(pixel_area(camera, place(local, pose)), 0, kDepth, 2.0);
  };
  f.da = depth(f.pa, ma);
  f.db = depth(f.pb, mb);
  return f;
}

TEST(StreamingOracle, SmallBudgetHoldsAndMissesNoContact) {
  const Scene& s = scene();
  ASSERT_GE(s.models.size(), 4u);
  Result<BakedFile> file = BakedFile::from_bytes(s.pack, "pack");
  ASSERT_TRUE(file.ok()) << file.error().message;
  // A few KB: about two trees at depth 5, less than the largest at depth 6.
  uint64_t largest6 = 0, largest5 = 0;
  for (const TreeInfo& t : file->trees()) {
    largest6 = std::max(largest6, 5 * t.raw_bytes[6]);
    largest5 = std::max(largest5, 5 * t.raw_bytes[5]);
  }
  const uint64_t budget = 2 * largest5;
  LevelCache cache(budget);
  for (size_t i = 0; i < s.models.size(); ++i) ASSERT_EQ(*cache.add(*file, i), TreeId(i));

  std::mt19937 rng(71);
  const int frames = pose_count(3000);
  int exact_hits = 0, shallower = 0, deep_asks = 0;
  for (int k = 0; k < frames; ++k) {
    const Frame f = random_frame(rng, s);
    deep_asks += (f.da == kDepth) + (f.db == kDepth);
    Result<int> ra = cache.require(TreeId(f.a), f.da);
    ASSERT_TRUE(ra.ok()) << ra.error().message;
    ASSERT_LE(cache.stats().bytes_held, budget) << "frame " << k;
    Result<int> rb = cache.require(TreeId(f.b), f.db);
    ASSERT_TRUE(rb.ok()) << rb.error().message;
    ASSERT_LE(cache.stats().bytes_held, budget) << "frame " << k;
    // Requiring b may have evicted levels of a: test at what is held now.
    const int ua = std::min(*ra, cache.held_depth(TreeId(f.a)));
    const int ub = std::min(*rb, cache.held_depth(TreeId(f.b)));
    shallower += (ua < f.da) + (ub < f.db);
    const PairTest streamed = collide({&cache.tree(TreeId(f.a)), f.pa, ua}, {&cache.tree(TreeId(f.b)), f.pb, ub});
    const fcl::CollisionObjectd oa(s.models[f.a].fcl, to_fcl(f.pa)), ob(s.models[f.b].fcl, to_fcl(f.pb));
    fcl::CollisionRequestd request;
    fcl::CollisionResultd result;
    fcl::collide(&oa, &ob, request, result);
    const bool exact = result.isCollision();
    exact_hits += exact;
    ASSERT_TRUE(streamed.hit || !exact) << "missed contact, frame " << k << " depths " << ua << "-" << ub;
  }
  const CacheStats& st = cache.stats();
  std::printf("  budget %llu B (largest tree at depth 6: %llu B); %d frames, %d contacts (FCL), %d objects tested "
              "shallower than asked; %llu decodes, %llu evictions, %llu clamps, peak %llu B\n",
              (unsigned long long)budget, (unsigned long long)largest6, frames, exact_hits, shallower,
              (unsigned long long)st.decodes, (unsigned long long)st.evictions, (unsigned long long)st.budget_clamps,
              (unsigned long long)st.peak_bytes_held);
  EXPECT_LE(st.peak_bytes_held, budget);
  EXPECT_GT(st.evictions, 0u);
  EXPECT_GT(st.budget_clamps, 0u);
  EXPECT_GT(shallower, 0);
  EXPECT_GT(deep_asks, frames / 10) << "the LOD asks for full depth often enough to matter";
  EXPECT_GT(exact_hits, frames * 3 / 10);
  EXPECT_LT(exact_hits, frames * 7 / 10);
}

TEST(StreamingOracle, UnlimitedBudgetEqualsFullLoadBitForBit) {
  const Scene& s = scene();
  Result<BakedFile> file = BakedFile::from_bytes(s.pack, "pack");
  ASSERT_TRUE(file.ok()) << file.error().message;
  LevelCache cache;
  std::vector<ObjectTree> full;
  for (size_t i = 0; i < s.models.size(); ++i) {
    ASSERT_TRUE(cache.add(*file, i).ok());
    full.push_back(*file->load(i, kDepth));
  }
  std::mt19937 rng(72);
  int hits = 0;
  const int frames = pose_count(1000);
  for (int k = 0; k < frames; ++k) {
    const Frame f = random_frame(rng, s);
    ASSERT_EQ(*cache.require(TreeId(f.a), f.da), f.da);
    ASSERT_EQ(*cache.require(TreeId(f.b), f.db), f.db);
    const PairTest streamed = collide({&cache.tree(TreeId(f.a)), f.pa, f.da}, {&cache.tree(TreeId(f.b)), f.pb, f.db});
    const PairTest loaded = collide({&full[f.a], f.pa, f.da}, {&full[f.b], f.pb, f.db});
    ASSERT_EQ(streamed.hit, loaded.hit) << "frame " << k;
    ASSERT_EQ(streamed.box_tests, loaded.box_tests) << "frame " << k;
    if (loaded.hit) {
      ASSERT_EQ(streamed.leaf.a, loaded.leaf.a) << "frame " << k;
      ASSERT_EQ(streamed.leaf.b, loaded.leaf.b) << "frame " << k;
    }
    hits += loaded.hit;
  }
  for (size_t i = 0; i < s.models.size(); ++i) {
    const ObjectTree& t = cache.tree(TreeId(i));
    for (int d = 0; d < t.loaded_depth(); ++d) ASSERT_EQ(t.masks().masks[d], full[i].masks().masks[d]);
  }
  EXPECT_EQ(cache.stats().evictions, 0u);
  EXPECT_GT(hits, frames * 3 / 10);
  EXPECT_LT(hits, frames * 7 / 10);
}

}  // namespace
}  // namespace octbake
