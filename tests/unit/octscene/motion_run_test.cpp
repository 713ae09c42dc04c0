// Scene motion through `octscene run` and run_scene(): spinning objects
// ("angular_velocity") and a moving camera ("camera_path"), the rules of
// docs/interface.md section 4 as World applies them, and bit-identical logs.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>

#include "helpers.h"
#include "run.h"
#include "scene.h"
#include "trade.h"

namespace octbake::scene {
namespace {

using namespace octbake::scene::testing;
using nlohmann::json;

const std::string kOctscene = OCTSCENE_BIN;
constexpr double kTimestep = 0.1;
constexpr double kRate = std::numbers::pi / 8;  // a quarter turn in 4 s = 40 frames

// The slab ([0, 4] x [0, 0.5] x [-1, 1], origin at its end) spins about +y
// through its origin; the cube "wall" ([-1, 1]^3 about (0, 0.25, -3.5)) is
// out of reach at frame 0 and in the slab's way about a quarter turn later.
json spinning_bar_scene(int frames) {
  return json{{"format", "octbake-scene/1"},
              {"baked", "baked"},
              {"camera", {{"position", {0, 20, -30}}, {"look_at", {0, 0, 0}}}},
              {"world", {{"min", {-50, -50, -50}}, {"max", {50, 50, 50}}, {"depth", 3}}},
              {"timestep", kTimestep},
              {"frames", frames},
              {"objects",
               {{{"name", "bar"}, {"model", "slab"}, {"position", {0, 0, 0}}, {"angular_velocity", {0, kRate, 0}}},
                {{"name", "wall"}, {"model", "cube"}, {"position", {0, 0.25, -3.5}}}}}};
}

// Signed separation of two convex polygons in the xz plane (> 0: apart),
// the largest gap over their edge normals.
double separation(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b) {
  double gap = -1e300;
  for (const auto* poly : {&a, &b}) {
    for (size_t i = 0; i < poly->size(); ++i) {
      const Eigen::Vector2d e = (*poly)[(i + 1) % poly->size()] - (*poly)[i];
      const Eigen::Vector2d n = Eigen::Vector2d(-e.y(), e.x()).normalized();
      double amin = 1e300, amax = -1e300, bmin = 1e300, bmax = -1e300;
      for (const auto& p : a) amin = std::min(amin, n.dot(p)), amax = std::max(amax, n.dot(p));
      for (const auto& p : b) bmin = std::min(bmin, n.dot(p)), bmax = std::max(bmax, n.dot(p));
      gap = std::max(gap, std::max(bmin - amax, amin - bmax));
    }
  }
  return gap;
}

// The bar's outline at frame f, by the rule itself (angle rate * f * dt
// about +y, which turns +x toward -z), independent of motion.h.
std::vector<Eigen::Vector2d> bar_at(int frame) {
  const double angle = kRate * frame * kTimestep;
  std::vector<Eigen::Vector2d> out;
  for (const auto& [x, z] : std::vector<std::pair<double, double>>{{0, -1}, {4, -1}, {4, 1}, {0, 1}})
    out.emplace_back(x * std::cos(angle) + z * std::sin(angle), -x * std::sin(angle) + z * std::cos(angle));
  return out;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream s(text);
  for (std::string line; std::getline(s, line);) lines.push_back(line);
  return lines;
}

// Needs World to spin objects (the app-driven world): until then the bar
// never turns and nothing is logged.
TEST(MotionRun, SpinningBarHitsItsNeighbourAtTheRightFrames) {
  const fs::path& dir = scratch_with_trees();
  constexpr int kFrames = 80;  // half a turn: in and out of the wall
  write_text(dir / "spin.json", spinning_bar_scene(kFrames).dump());
  Command c = run_command(kOctscene + " run " + (dir / "spin.json").string() +
                              " --response none --lod fixed --max-depth 3 --log " + (dir / "spin.csv").string(),
                          dir);
  ASSERT_EQ(c.status, 0) << c.err;
  std::set<int> logged;
  for (const std::string& line : lines_of(read_text(dir / "spin.csv"))) {
    if (line.rfind("frame,", 0) == 0) continue;
    logged.insert(std::stoi(line));
    EXPECT_NE(line.find(",bar,wall,3,3,"), std::string::npos) << line;
    // Spinning does not move the bar's origin.
    EXPECT_NE(line.find(",0,0,0,0,0.25,-3.5"), std::string::npos) << line;
  }
  const std::vector<Eigen::Vector2d> wall{{-1, -4.5}, {1, -4.5}, {1, -2.5}, {-1, -2.5}};
  int touching = 0, first = -1;
  for (int f = 0; f < kFrames; ++f) {
    const double gap = separation(bar_at(f), wall);
    if (gap < 0 && first < 0) first = f;
    if (std::abs(gap) < 0.02) continue;  // too close to call
    touching += gap < 0;
    EXPECT_EQ(logged.count(f), gap < 0 ? 1u : 0u) << "frame " << f << ": gap " << gap;
  }
  EXPECT_GT(first, 20);   // only after most of a quarter turn
  EXPECT_GT(touching, 15);  // not vacuous
  EXPECT_LT(touching, 60);
}

// trade takes its poses from World: the exact answer sees the bar spin.
// Needs World to spin objects (the app-driven world).
TEST(MotionRun, TradeScoresSpinningPosesWithRecallOne) {
  const fs::path& dir = scratch_with_trees();
  Result<Scene> scene = parse_scene(spinning_bar_scene(80).dump(), dir.string());
  ASSERT_TRUE(scene) << scene.error().message;
  Result<ModelLibrary> library = ModelLibrary::open(scene->baked);
  ASSERT_TRUE(library);
  TradeOptions options;
  options.meshes = dir.string();
  options.max_depth = 3;
  Result<TradeReport> report = run_trade(*scene, *library, options);
  ASSERT_TRUE(report) << report.error().message;
  EXPECT_GT(report->exact_contacts, 15u);
  EXPECT_LT(report->exact_contacts, 60u);
  EXPECT_TRUE(report->misses.empty());
  for (const TradeRow& row : report->rows) {
    EXPECT_EQ(row.false_negatives, 0u) << row.label;
    EXPECT_EQ(row.true_positives, report->exact_contacts) << row.label;
  }
}

// Static cubes at several distances and a camera flying in from far away.
json camera_path_scene() {
  json objects = json::array();
  for (int k = 0; k < 6; ++k)
    objects.push_back({{"name", "c" + std::to_string(k)}, {"model", "cube"}, {"position", {3.0 * k, 0, 15.0 * k}}});
  return json{{"format", "octbake-scene/1"},
              {"baked", "baked"},
              {"camera", {{"position", {0, 40, -400}}, {"look_at", {0, 0, 40}}, {"viewport", {800, 600}}}},
              {"camera_path",
               {{{"frame", 5}, {"position", {0, 2, -2000}}, {"look_at", {0, 0, 0}}},
                {{"frame", 45}, {"position", {1, 2, -8}}, {"look_at", {0, 0, 30}}},
                {{"frame", 60}, {"position", {40, 3, 40}}, {"look_at", {0, 0, 40}}}}},
              {"world", {{"min", {-100, -100, -100}}, {"max", {100, 100, 100}}, {"depth", 3}}},
              {"timestep", kTimestep},
              {"frames", 70},
              {"objects", objects}};
}

std::vector<int> depths_of(const World& w) {
  std::vector<int> d;
  for (size_t i = 0; i < w.size(); ++i) d.push_back(w.depth(i));
  return d;
}

// Needs World to follow the camera path (the app-driven world).
TEST(MotionRun, CameraPathChoosesTheDepthsOfTheFramesCamera) {
  const fs::path& dir = scratch_with_trees();
  Result<Scene> scene = parse_scene(camera_path_scene().dump(), dir.string());
  ASSERT_TRUE(scene) << scene.error().message;
  Result<ModelLibrary> library = ModelLibrary::open(scene->baked);
  ASSERT_TRUE(library);
  Result<SceneModels> models = load_scene_models(*scene, *library, 12);
  ASSERT_TRUE(models);
  for (bool every_frame : {false, true}) {
    RunOptions options;
    options.lod = {LodPolicy::screen, 1, 4, 1.0};
    options.response = Response::none;
    options.areas_every_frame = every_frame;
    std::vector<std::vector<int>> depths;
    ASSERT_TRUE(run_scene(*scene, *models, options, [&](const FrameReport& f) {
      depths.push_back(depths_of(*f.world));
    }));
    ASSERT_EQ(depths.size(), 70u);
    std::set<std::vector<int>> distinct;
    for (int f : {0, 5, 12, 25, 38, 45, 52, 60, 69}) {
      // The oracle: the same scene with the frame's camera fixed, one frame.
      Scene still = *scene;
      still.camera = camera_on_path(scene->camera, scene->camera_path, f);
      still.camera_path.clear();
      RunOptions one = options;
      one.frames = 1;
      std::vector<int> want;
      ASSERT_TRUE(run_scene(still, *models, one, [&](const FrameReport& r) { want = depths_of(*r.world); }));
      EXPECT_EQ(depths[static_cast<size_t>(f)], want) << "frame " << f << (every_frame ? " (areas every frame)" : "");
      distinct.insert(want);
    }
    EXPECT_GE(distinct.size(), 3u);  // the path really changes the depths
  }
}

// Holds in every branch: spinning, flying scenes log the same bytes on every
// run and for every thread count.
TEST(MotionRun, SpinAndCameraPathLogsAreByteIdenticalAcrossRunsAndThreads) {
  const fs::path& dir = scratch_with_trees();
  Command g = run_command(kOctscene + " gen --static 20 --moving 25 --seed 4 --models cube,slab --world 36 " +
                              "--speed 7 --frames 250 --rotated-share 1 --spin-share 0.6 --spin-rate 3 " +
                              "--camera-path 5 --baked " + (dir / "baked").string() + " --baked-as baked",
                          dir);
  ASSERT_EQ(g.status, 0) << g.err;
  write_text(dir / "whirl.json", g.out);
  for (const char* response : {"none", "separate"}) {
    std::string first;
    for (const char* threads : {"1", "1", "2", "3"}) {
      const fs::path log = dir / "whirl.csv";
      Command c = run_command(kOctscene + " run " + (dir / "whirl.json").string() + " --response " + response +
                                  " --threads " + threads + " --log " + log.string(),
                              dir);
      ASSERT_EQ(c.status, 0) << c.err;
      const std::string text = read_text(log);
      if (first.empty()) first = text;
      EXPECT_EQ(text, first) << response << ", --threads " << threads;
    }
    EXPECT_GT(lines_of(first).size(), 10u) << response << ": too few collisions to test";
  }
}

TEST(MotionRun, ThreadsMustBePositive) {
  const fs::path& dir = scratch_with_trees();
  write_text(dir / "spin.json", spinning_bar_scene(5).dump());
  for (const char* bad : {"0", "-2", "many"}) {
    Command c = run_command(kOctscene + " run " + (dir / "spin.json").string() + " --threads " + bad, dir);
    EXPECT_EQ(c.status, 2) << bad;
    EXPECT_NE(c.err.find("--threads"), std::string::npos) << c.err;
    c = run_command(kOctscene + " trade " + (dir / "spin.json").string() + " --meshes " + dir.string() +
                        " --threads " + bad,
                    dir);
    EXPECT_EQ(c.status, 2) << bad;
    EXPECT_NE(c.err.find("--threads"), std::string::npos) << c.err;
  }
  Result<Scene> scene = parse_scene(spinning_bar_scene(5).dump(), dir.string());
  ASSERT_TRUE(scene);
  Result<ModelLibrary> library = ModelLibrary::open(scene->baked);
  ASSERT_TRUE(library);
  RunOptions options;
  options.threads = 0;
  Result<RunResult> r = run_scene(*scene, *library, options, {});
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message, "threads: must be >= 1");
}

}  // namespace
}  // namespace octbake::scene
