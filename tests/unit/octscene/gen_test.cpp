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

}  // namespace
}  // namespace octbake::scene
