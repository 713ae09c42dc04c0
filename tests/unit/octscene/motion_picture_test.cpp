// `octscene picture scene --frame F` on a scene with a camera path draws
// frame F from the camera the path gives at F.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "helpers.h"

namespace octbake::scene {
namespace {

using namespace octbake::scene::testing;
using nlohmann::json;

const std::string kOctscene = OCTSCENE_BIN;

json still_life(const json& camera) {
  json objects = json::array();
  for (int k = 0; k < 5; ++k)
    objects.push_back({{"name", "c" + std::to_string(k)}, {"model", k % 2 ? "slab" : "cube"},
                       {"position", {4.0 * k - 8, 0.5 * k, 3.0 * k}}});
  return json{{"format", "octbake-scene/1"}, {"baked", "baked"},     {"camera", camera},
              {"world", {{"min", {-60, -60, -60}}, {"max", {60, 60, 60}}, {"depth", 3}}},
              {"timestep", 0.1},          {"frames", 50},        {"objects", objects}};
}

std::string picture(const fs::path& dir, const std::string& scene, int frame) {
  const fs::path png = dir / ("pic_" + scene + std::to_string(frame) + ".png");
  Command c = run_command(kOctscene + " picture scene " + (dir / (scene + ".json")).string() + " --frame " +
                              std::to_string(frame) + " --lod fixed --max-depth 2 --width 200 --meshes " +
                              dir.string() + " --out " + png.string(),
                          dir);
  EXPECT_EQ(c.status, 0) << c.err;
  return read_text(png);
}

TEST(MotionPicture, FrameIsDrawnFromThePathsCamera) {
  const fs::path& dir = scratch_with_trees();
  const json base = {{"position", {0, 30, -80}}, {"look_at", {0, 0, 0}}, {"viewport", {400, 300}}};
  json flying = still_life(base);
  flying["camera_path"] = {{{"frame", 0}, {"position", {-30, 10, -30}}, {"look_at", {0, 0, 5}}},
                           {{"frame", 40}, {"position", {30, 2, -10}}, {"look_at", {0, 0, 5}}}};
  write_text(dir / "flying.json", flying.dump());
  // Frame 20 of the path: half way between the keys.
  json at20 = base;
  at20["position"] = {0, 6, -20};
  at20["look_at"] = {0, 0, 5};
  write_text(dir / "still20.json", still_life(at20).dump());
  json at40 = base;
  at40["position"] = {30, 2, -10};
  at40["look_at"] = {0, 0, 5};
  write_text(dir / "still40.json", still_life(at40).dump());

  const std::string f20 = picture(dir, "flying", 20), f45 = picture(dir, "flying", 45);
  ASSERT_FALSE(f20.empty());
  EXPECT_TRUE(f20 == picture(dir, "still20", 20)) << "frame 20 is not drawn from the path's camera";
  EXPECT_TRUE(f45 == picture(dir, "still40", 45)) << "after the last key the camera stays at it";
  EXPECT_FALSE(f20 == f45);
  EXPECT_FALSE(f20 == picture(dir, "flying", 0));
}

}  // namespace
}  // namespace octbake::scene
