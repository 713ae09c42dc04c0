// The thesis's experiment scenes shipped in assets/scenes/ stay valid: they
// parse, have the thesis's object counts, and name only bundled models.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "scene.h"

namespace octbake::scene {
namespace {

struct Expected {
  const char* file;
  size_t statics, moving;
};

class BundledScene : public testing::TestWithParam<Expected> {};

TEST_P(BundledScene, ParsesWithTheThesisCounts) {
  const std::filesystem::path root = OCTBAKE_SOURCE_DIR;
  const Expected want = GetParam();
  Result<Scene> scene = load_scene((root / "assets/scenes" / want.file).string());
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  EXPECT_EQ(scene->frames, 7200);  // 240 s at 30 frames a second
  EXPECT_NEAR(scene->timestep, 1.0 / 30.0, 1e-9);
  size_t moving = 0;
  for (const SceneObject& o : scene->objects) {
    moving += o.velocity != Eigen::Vector3d::Zero();
    EXPECT_TRUE(std::filesystem::exists(root / "assets" / (o.model + ".obj"))) << o.name << ": " << o.model;
  }
  EXPECT_EQ(scene->objects.size() - moving, want.statics);
  EXPECT_EQ(moving, want.moving);
}

INSTANTIATE_TEST_SUITE_P(Thesis, BundledScene,
                         testing::Values(Expected{"test1.json", 100, 50}, Expected{"test2.json", 140, 70}));

}  // namespace
}  // namespace octbake::scene
