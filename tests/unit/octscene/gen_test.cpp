// `octscene gen`: reproducible for a seed, overlap-free, inside the world,
// and accepted by parse_scene.
#include <gtest/gtest.h>

#include "gen.h"
#include "helpers.h"
#include "scene.h"

namespace octbake::scene {
namespace {

using namespace octbake::scene::testing;

const std::string kOctscene = OCTSCENE_BIN;

std::string gen_command(const fs::path& dir, int statics, int moving, uint32_t seed, double world) {
  return kOctscene + " gen --static " + std::to_string(statics) + " --moving " + std::to_string(moving) +
         " --seed " + std::to_string(seed) + " --models cube,slab --world " + std::to_string(world) +
         " --baked " + (dir / "baked").string() + " --baked-as baked";
}

bool overlap(const Aabb& a, const Aabb& b) {
  return (a.min.array() <= b.max.array()).all() && (b.min.array() <= a.max.array()).all();
}

TEST(Gen, SameSeedSameBytesOtherSeedOtherScene) {
  const fs::path& dir = scratch_with_trees();
  Command a = run_command(gen_command(dir, 30, 20, /*seed=*/5, 40), dir);
  Command b = run_command(gen_command(dir, 30, 20, /*seed=*/5, 40), dir);
  Command c = run_command(gen_command(dir, 30, 20, /*seed=*/6, 40), dir);
  ASSERT_EQ(a.status, 0) << a.err;
  EXPECT_EQ(a.out, b.out);
  EXPECT_NE(a.out, c.out);
}

TEST(Gen, ScenesParseAndStartWithoutOverlaps) {
  const fs::path& dir = scratch_with_trees();
  Result<ModelLibrary> library = ModelLibrary::open((dir / "baked").string());
  ASSERT_TRUE(library) << library.error().message;
  std::map<std::string, Aabb> bounds;
  for (const char* m : {"cube", "slab"}) bounds[m] = library->info(m)->bounds;

  int touching_pairs = 0;  // AABBs within one unit: the placement was really tested
  for (uint32_t seed = 1; seed <= 6; ++seed) {
    const int statics = 25 + static_cast<int>(seed) * 5, moving = 20;
    Command g = run_command(gen_command(dir, statics, moving, seed, 30), dir);
    ASSERT_EQ(g.status, 0) << g.err;
    Result<Scene> scene = parse_scene(g.out, dir.string());
    ASSERT_TRUE(scene) << scene.error().message;
    EXPECT_EQ(scene->baked, (dir / "baked").string());
    ASSERT_EQ(scene->objects.size(), static_cast<size_t>(statics + moving));
    std::vector<Aabb> boxes;
    for (size_t i = 0; i < scene->objects.size(); ++i) {
      const SceneObject& o = scene->objects[i];
      EXPECT_EQ(o.velocity.isZero(0), i < static_cast<size_t>(statics)) << o.name;
      EXPECT_EQ(o.name.rfind(o.model + "_", 0), 0u) << o.name;
      Aabb box = world_bounds(place(bounds.at(o.model), o.pose));
      EXPECT_TRUE((box.min.array() >= scene->world.min.array()).all() &&
                  (box.max.array() <= scene->world.max.array()).all())
          << o.name << " leaves the world";
      for (size_t k = 0; k < boxes.size(); ++k) {
        EXPECT_FALSE(overlap(box, boxes[k])) << o.name << " overlaps " << scene->objects[k].name;
        Aabb grown{boxes[k].min.array() - 1.0, boxes[k].max.array() + 1.0};
        touching_pairs += overlap(box, grown);
      }
      boxes.push_back(box);
    }
  }
  EXPECT_GT(touching_pairs, 20);
}

TEST(Gen, ImpossiblePlacementIsAnError) {
  const fs::path& dir = scratch_with_trees();
  Command g = run_command(gen_command(dir, 200, 0, 1, 6), dir);
  EXPECT_EQ(g.status, 1);
  EXPECT_NE(g.err.find("use a larger --world"), std::string::npos) << g.err;
  g = run_command(kOctscene + " gen --static 1 --moving 0 --seed 1 --models cat --baked " + (dir / "baked").string(),
                  dir);
  EXPECT_EQ(g.status, 1);
  EXPECT_NE(g.err.find("cat"), std::string::npos) << g.err;
}

// ---- sizes, orientations, spin and the camera path ----

Result<Scene> gen_scene(const fs::path& dir, const std::string& extra, int statics = 40, int moving = 40,
                        double world = 60) {
  Command g = run_command(gen_command(dir, statics, moving, /*seed=*/9, world) + " --frames 300 " + extra, dir);
  if (g.status != 0) return Error{ErrorCode::invalid_argument, g.err};
  return parse_scene(g.out, dir.string());
}

TEST(GenMotion, DefaultsDrawNothingNew) {
  // The motion options at their defaults give the very bytes of a scene
  // generated without them (the bundled scenes stay reproducible).
  const fs::path& dir = scratch_with_trees();
  Command a = run_command(gen_command(dir, 30, 20, 5, 40), dir);
  Command b = run_command(gen_command(dir, 30, 20, 5, 40) +
                              " --scale-range 1,1 --rotated-share 0 --spin-share 0 --spin-rate 3 --resting-share 0",
                          dir);
  ASSERT_EQ(a.status, 0) << a.err;
  ASSERT_EQ(b.status, 0) << b.err;
  EXPECT_EQ(a.out, b.out);
  EXPECT_EQ(a.out.find("angular_velocity"), std::string::npos);
  EXPECT_EQ(a.out.find("camera_path"), std::string::npos);
}

TEST(GenMotion, ScaleRangeIsLogUniformAndPlacedWithoutOverlaps) {
  const fs::path& dir = scratch_with_trees();
  Result<ModelLibrary> library = ModelLibrary::open((dir / "baked").string());
  ASSERT_TRUE(library);
  Result<Scene> s = gen_scene(dir, "--scale-range 0.05,20", 60, 20, 400);
  ASSERT_TRUE(s) << s.error().message;
  double lo = 1e300, hi = 0;
  int below_one = 0;
  std::vector<Aabb> boxes;
  for (const SceneObject& o : s->objects) {
    EXPECT_GE(o.pose.scale, 0.05);
    EXPECT_LE(o.pose.scale, 20);
    lo = std::min(lo, o.pose.scale), hi = std::max(hi, o.pose.scale);
    below_one += o.pose.scale < 1;  // log-uniform: half of them
    Aabb box = world_bounds(place(library->info(o.model)->bounds, o.pose));
    for (const Aabb& b : boxes) EXPECT_FALSE(overlap(box, b)) << o.name;
    boxes.push_back(box);
  }
  EXPECT_GT(hi / lo, 100);
  EXPECT_GT(below_one, 0.3 * 80);
  EXPECT_LT(below_one, 0.7 * 80);
}

TEST(GenMotion, RotatedAndSpinningShares) {
  const fs::path& dir = scratch_with_trees();
  Result<ModelLibrary> library = ModelLibrary::open((dir / "baked").string());
  ASSERT_TRUE(library);
  Result<Scene> s = gen_scene(dir, "--rotated-share 1 --spin-share 0.5 --spin-rate 2", 40, 40, 80);
  ASSERT_TRUE(s) << s.error().message;
  int spinning = 0, spinning_statics = 0;
  std::vector<Aabb> boxes;
  for (size_t i = 0; i < s->objects.size(); ++i) {
    const SceneObject& o = s->objects[i];
    // A full 3D orientation: not a turn about y alone.
    EXPECT_GT(std::abs(o.pose.rotation.x()) + std::abs(o.pose.rotation.z()), 1e-6) << o.name;
    const double rate = o.angular_velocity.norm();
    if (rate > 0) {
      ++spinning;
      spinning_statics += i < 40;
      EXPECT_GE(rate, 1.0);
      EXPECT_LT(rate, 2.0);
    }
    // Spinning or not, no two objects can touch at any orientation of the
    // spinners: each one's box is that of the sphere it spins in.
    const Aabb local = library->info(o.model)->bounds;
    double r = 0;
    for (int c = 0; c < 8; ++c)
      r = std::max(r, Eigen::Vector3d((c & 1) ? local.max.x() : local.min.x(), (c & 2) ? local.max.y() : local.min.y(),
                                      (c & 4) ? local.max.z() : local.min.z()).norm());
    Aabb box = rate > 0 ? Aabb{o.pose.position.array() - r, o.pose.position.array() + r}
                        : world_bounds(place(local, o.pose));
    for (const Aabb& b : boxes) EXPECT_FALSE(overlap(box, b)) << o.name;
    boxes.push_back(box);
  }
  EXPECT_GT(spinning, 0.3 * 80);
  EXPECT_LT(spinning, 0.7 * 80);
  EXPECT_GT(spinning_statics, 0);  // statics spin too (and so are moving)
  Result<Scene> yaw = gen_scene(dir, "--rotated-share 0 --spin-share 0");
  ASSERT_TRUE(yaw);
  for (const SceneObject& o : yaw->objects) {
    EXPECT_EQ(o.pose.rotation.x(), 0) << o.name;
    EXPECT_EQ(o.pose.rotation.z(), 0) << o.name;
    EXPECT_TRUE(o.angular_velocity.isZero(0));
  }
}

// A resting static overlaps exactly one earlier box, a static's, by a fifth
// of the smaller extent on one axis (a little more where the world's walls
// moved it); every other box starts apart from all earlier ones.
TEST(GenMotion, RestingStaticsLeanOnOneEarlierStatic) {
  const fs::path& dir = scratch_with_trees();
  Result<ModelLibrary> library = ModelLibrary::open((dir / "baked").string());
  ASSERT_TRUE(library);
  const int statics = 60, moving = 30;
  Result<Scene> s = gen_scene(dir, "--resting-share 0.6 --rotated-share 0.5", statics, moving, 40);
  ASSERT_TRUE(s) << s.error().message;
  std::vector<Aabb> boxes;
  int resting = 0;
  for (size_t i = 0; i < s->objects.size(); ++i) {
    const SceneObject& o = s->objects[i];
    const Aabb box = world_bounds(place(library->info(o.model)->bounds, o.pose));
    EXPECT_TRUE((box.min.array() >= s->world.min.array()).all() && (box.max.array() <= s->world.max.array()).all())
        << o.name << " leaves the world";
    std::vector<size_t> met;
    for (size_t j = 0; j < boxes.size(); ++j)
      if (overlap(box, boxes[j])) met.push_back(j);
    if (i >= size_t(statics)) {
      EXPECT_TRUE(met.empty()) << o.name << " is moving and starts in contact";
    } else if (!met.empty()) {
      ++resting;
      ASSERT_EQ(met.size(), 1u) << o.name << " rests on more than one box";
      // Sunk by at least a fifth of the smaller extent on some axis (less
      // only by rounding), and at most the whole box.
      const Aabb& other = boxes[met[0]];
      const Eigen::Vector3d depth = box.max.cwiseMin(other.max) - box.min.cwiseMax(other.min);
      const Eigen::Vector3d smaller = (box.max - box.min).cwiseMin(other.max - other.min);
      EXPECT_GE((depth.array() / smaller.array()).minCoeff(), 0.2 * (1 - 1e-9)) << o.name;
    }
    boxes.push_back(box);
  }
  EXPECT_GT(resting, 0.4 * (statics - 1));
  EXPECT_LT(resting, 0.8 * (statics - 1));
  // Without it, every box starts apart (the test above would count none).
  Result<Scene> apart = gen_scene(dir, "", statics, moving, 40);
  ASSERT_TRUE(apart);
  boxes.clear();
  for (const SceneObject& o : apart->objects) {
    const Aabb box = world_bounds(place(library->info(o.model)->bounds, o.pose));
    for (const Aabb& b : boxes) EXPECT_FALSE(overlap(box, b)) << o.name;
    boxes.push_back(box);
  }
}

TEST(GenMotion, CameraPathFliesThroughTheWorld) {
  const fs::path& dir = scratch_with_trees();
  Result<Scene> s = gen_scene(dir, "--camera-path 7", 20, 20, 80);
  ASSERT_TRUE(s) << s.error().message;
  ASSERT_EQ(s->camera_path.size(), 7u);
  EXPECT_EQ(s->camera_path.front().frame, 0);
  EXPECT_EQ(s->camera_path.back().frame, 300);
  EXPECT_EQ(s->camera.position, s->camera_path.front().position);
  for (const CameraKey& k : s->camera_path) {
    EXPECT_TRUE((k.position.array().abs() < 40).all()) << "key at frame " << k.frame << " is outside the world";
    EXPECT_GT(k.position.norm(), 10) << "the loop goes around the centre";
  }
}

// Every key count gives a path parse_scene accepts: the view never degenerates
// between keys (3 keys once passed through the centre looking along up).
TEST(GenMotion, EveryCameraKeyCountParses) {
  const fs::path& dir = scratch_with_trees();
  for (int keys = 2; keys <= 12; ++keys) {
    Result<Scene> s = gen_scene(dir, "--camera-path " + std::to_string(keys), 5, 5, 80);
    ASSERT_TRUE(s) << keys << " keys: " << s.error().message;
    EXPECT_EQ(s->camera_path.size(), size_t(keys));
  }
}

TEST(GenMotion, BadOptionsAreErrors) {
  const fs::path& dir = scratch_with_trees();
  for (const auto& [extra, expected] : std::vector<std::pair<std::string, std::string>>{
           {"--scale-range 2,1", "--scale-range"},
           {"--scale-range 0,1", "--scale-range"},
           {"--scale-range 1", "--scale-range"},
           {"--rotated-share 1.5", "--rotated-share"},
           {"--spin-share -0.1", "--spin-share"},
           {"--spin-rate -1", "--spin-rate"},
           {"--resting-share 1.5", "--resting-share"},
           {"--resting-share nan", "--resting-share"},
           {"--camera-path 1", "--camera-path"},
           {"--camera-path 400", "--camera-path"},  // more keys than frames
       }) {
    Command g = run_command(gen_command(dir, 5, 5, 1, 40) + " --frames 300 " + extra, dir);
    EXPECT_NE(g.status, 0) << extra;
    EXPECT_NE(g.err.find(expected), std::string::npos) << extra << ": " << g.err;
  }
}

}  // namespace
}  // namespace octbake::scene
