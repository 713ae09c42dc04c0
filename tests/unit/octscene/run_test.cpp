// `octscene run` end to end on trees baked by the octbake CLI, and run_scene()
// as a library call.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "helpers.h"
#include "run.h"
#include "scene.h"

namespace octbake::scene {
namespace {

using namespace octbake::scene::testing;
using nlohmann::json;

const std::string kOctscene = OCTSCENE_BIN;

// Cube "b" slides along +x through cube "a" (both [-1, 1]^3, axis aligned):
// they overlap exactly while |xb - xa| <= 2.
json sliding_scene(int frames) {
  return json{{"format", "octbake-scene/1"},
              {"baked", "baked"},
              {"camera", {{"position", {0, 5, -30}}, {"look_at", {0, 0, 0}}}},
              {"world", {{"min", {-50, -50, -50}}, {"max", {50, 50, 50}}, {"depth", 3}}},
              {"timestep", 0.1},
              {"frames", frames},
              {"objects",
               {{{"name", "a"}, {"model", "cube"}, {"position", {0, 0, 0}}},
                {{"name", "b"}, {"model", "cube"}, {"position", {-6, 0.5, 0.25}}, {"velocity", {1, 0, 0}}},
                {{"name", "far"}, {"model", "slab"}, {"position", {30, 30, 30}}}}}};
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream s(text);
  for (std::string line; std::getline(s, line);) lines.push_back(line);
  return lines;
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream s(line);
  for (std::string field; std::getline(s, field, ',');) out.push_back(field);
  return out;
}

TEST(Run, ResponseNoneLogsThePairEveryOverlappingFrame) {
  const fs::path& dir = scratch_with_trees();
  write_text(dir / "slide.json", sliding_scene(/*frames=*/120).dump());
  Command c = run_command(kOctscene + " run " + (dir / "slide.json").string() + " --response none --lod fixed " +
                              "--max-depth 3 --log " + (dir / "slide.csv").string(),
                          dir);
  ASSERT_EQ(c.status, 0) << c.err;
  std::vector<std::string> lines = lines_of(read_text(dir / "slide.csv"));
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines[0], "frame,time,a,b,depth_a,depth_b,box_tests,ax,ay,az,bx,by,bz");
  std::map<int, std::vector<std::string>> logged;
  for (size_t i = 1; i < lines.size(); ++i) {
    std::vector<std::string> f = split(lines[i]);
    ASSERT_EQ(f.size(), 13u) << lines[i];
    EXPECT_EQ(logged.count(std::stoi(f[0])), 0u) << "pair logged twice in frame " << f[0];
    logged[std::stoi(f[0])] = f;
  }
  int overlapping = 0;
  for (int frame = 0; frame < 120; ++frame) {
    const double xb = -6 + 0.1 * frame;
    const double gap = std::abs(xb) - 2;  // < 0: the cubes overlap
    if (std::abs(gap) < 0.05) continue;   // too close to touching to call
    if (gap < 0) {
      ++overlapping;
      ASSERT_EQ(logged.count(frame), 1u) << "frame " << frame << " overlaps but was not logged";
      const std::vector<std::string>& f = logged[frame];
      EXPECT_EQ(f[2], "a");
      EXPECT_EQ(f[3], "b");
      EXPECT_EQ(std::stod(f[1]), frame * 0.1);
      EXPECT_EQ(f[4], "3");
      EXPECT_EQ(f[5], "3");
      EXPECT_GT(std::stoull(f[6]), 0u);
      EXPECT_EQ(std::stod(f[7]), 0.0);
      EXPECT_NEAR(std::stod(f[10]), xb, 1e-9);
      EXPECT_EQ(std::stod(f[11]), 0.5);
      EXPECT_EQ(std::stod(f[12]), 0.25);
    } else {
      // The cubes' depth-3 boxes are exactly their bounds: no slack to report.
      EXPECT_EQ(logged.count(frame), 0u) << "frame " << frame << " is separated but was logged";
    }
  }
  EXPECT_GT(overlapping, 30);  // not vacuous: b spends 4 s inside a
}

TEST(Run, LogsAreByteIdenticalAcrossRuns) {
  const fs::path& dir = scratch_with_trees();
  // Crowded enough that every response has work to do.
  Command g = run_command(kOctscene + " gen --static 20 --moving 30 --seed 7 --models cube,slab --world 30 " +
                              "--speed 6 --frames 250 --baked " + (dir / "baked").string() + " --baked-as baked",
                          dir);
  ASSERT_EQ(g.status, 0) << g.err;
  write_text(dir / "crowd.json", g.out);
  // Each response once, each LOD policy once (kept small for sanitizer builds).
  for (const auto& [response, lod] : std::vector<std::pair<std::string, std::string>>{
           {"none", "fixed"}, {"thesis", "thesis"}, {"separate", "screen"}}) {
    std::string logs[2];
    for (int run = 0; run < 2; ++run) {
      fs::path log = dir / ("crowd_" + std::to_string(run) + ".csv");
      Command c = run_command(kOctscene + " run " + (dir / "crowd.json").string() + " --response " + response +
                                  " --lod " + lod + " --log " + log.string(),
                              dir);
      ASSERT_EQ(c.status, 0) << c.err;
      logs[run] = read_text(log);
    }
    EXPECT_EQ(logs[0], logs[1]) << response << " " << lod;
    EXPECT_GT(lines_of(logs[0]).size(), 10u) << response << " " << lod << ": too few collisions to test";
  }
}

TEST(Run, SummaryJsonHasEveryKey) {
  const fs::path& dir = scratch_with_trees();
  write_text(dir / "slide.json", sliding_scene(/*frames=*/60).dump());
  Command c = run_command(kOctscene + " run " + (dir / "slide.json").string() + " --summary json --response none " +
                              "--lod thesis --min-depth 1 --max-depth 3",
                          dir);
  ASSERT_EQ(c.status, 0) << c.err;
  json j = json::parse(c.out);
  for (const char* key : {"frames", "collisions", "depth_pairs", "box_tests", "pair_tests", "load_ms",
                          "frame_ms_mean", "frame_ms_p99", "peak_rss_mb"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["frames"], 60);
  ASSERT_TRUE(j["depth_pairs"].is_object());
  uint64_t sum = 0;
  for (const auto& [key, n] : j["depth_pairs"].items()) {
    int lo = 0, hi = 0;
    ASSERT_EQ(std::sscanf(key.c_str(), "%d-%d", &lo, &hi), 2) << key;
    EXPECT_LE(lo, hi);
    sum += n.get<uint64_t>();
  }
  EXPECT_EQ(sum, j["collisions"].get<uint64_t>());
  // b overlaps a from x = -2 (frame 40) on: at least frames 41..59.
  EXPECT_GE(j["collisions"].get<uint64_t>(), 19u);
  EXPECT_GE(j["pair_tests"].get<uint64_t>(), j["collisions"].get<uint64_t>());
  EXPECT_GT(j["peak_rss_mb"].get<double>(), 0);
}

// Two static cubes resting against each other: tested on frame 0, then
// answered by the frame before's result (0 box tests) while the third cube
// slides past elsewhere.
TEST(Run, RestingPairIsReusedWithZeroBoxTests) {
  const fs::path& dir = scratch_with_trees();
  json scene = sliding_scene(/*frames=*/30);
  scene["objects"][0]["position"] = {20, 0, 0};  // a, away from b's path
  scene["objects"][2] = {{"name", "c"}, {"model", "cube"}, {"position", {21.5, 0.25, 0}}};
  write_text(dir / "rest.json", scene.dump());
  Command c = run_command(kOctscene + " run " + (dir / "rest.json").string() + " --summary json --response none " +
                              "--lod fixed --max-depth 3 --log " + (dir / "rest.csv").string(),
                          dir);
  ASSERT_EQ(c.status, 0) << c.err;
  const json j = json::parse(c.out);
  EXPECT_EQ(j["collisions"], 30);
  EXPECT_EQ(j["pair_tests"], 30);
  EXPECT_EQ(j["pairs_reused"], 29);
  const std::vector<std::string> lines = lines_of(read_text(dir / "rest.csv"));
  ASSERT_EQ(lines.size(), 31u);
  for (size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string> f = split(lines[i]);
    ASSERT_EQ(f.size(), 13u);
    EXPECT_EQ(f[2] + f[3], "ac");
    EXPECT_EQ(std::stoull(f[6]) > 0, i == 1) << lines[i];
  }
  EXPECT_EQ(j["box_tests"].get<uint64_t>(), std::stoull(split(lines[1])[6]));
  // The text summary says it too.
  c = run_command(kOctscene + " run " + (dir / "rest.json").string() + " --response none --lod fixed --max-depth 3",
                  dir);
  ASSERT_EQ(c.status, 0) << c.err;
  EXPECT_NE(c.out.find("pair tests       30 (29 reused)"), std::string::npos) << c.out;
}

TEST(Run, FramesOptionOverridesTheScene) {
  const fs::path& dir = scratch_with_trees();
  write_text(dir / "slide.json", sliding_scene(/*frames=*/60).dump());
  Command c = run_command(kOctscene + " run " + (dir / "slide.json").string() + " --summary json --frames 7", dir);
  ASSERT_EQ(c.status, 0) << c.err;
  EXPECT_EQ(json::parse(c.out)["frames"], 7);
}

TEST(Run, MissingModelIsNamedWithItsPath) {
  const fs::path& dir = scratch_with_trees();
  json j = sliding_scene(10);
  j["objects"][2]["model"] = "cat";
  write_text(dir / "cat.json", j.dump());
  Command c = run_command(kOctscene + " run " + (dir / "cat.json").string(), dir);
  EXPECT_EQ(c.status, 1);
  EXPECT_EQ(c.err, "octscene: error: " + (dir / "cat.json").string() + ": objects[2].model: no tree \"cat\" in " +
                       (dir / "baked").string() + "\n");
}

TEST(Run, BadSceneIsOneErrorLineAndExitOne) {
  const fs::path& dir = scratch_with_trees();
  json j = sliding_scene(10);
  j["objects"][1]["rotation"] = {0, 0, 0.5, 0.5};
  write_text(dir / "rot.json", j.dump());
  Command c = run_command(kOctscene + " run " + (dir / "rot.json").string(), dir);
  EXPECT_EQ(c.status, 1);
  EXPECT_EQ(c.err,
            "octscene: error: " + (dir / "rot.json").string() + ": objects[1].rotation: not a unit quaternion\n");
  write_text(dir / "broken.json", "{\"format\": }");
  c = run_command(kOctscene + " run " + (dir / "broken.json").string(), dir);
  EXPECT_EQ(c.status, 1);
  EXPECT_NE(c.err.find("broken.json: invalid JSON at line 1, column 12"), std::string::npos) << c.err;
}

TEST(Run, UsageErrorsExitTwo) {
  const fs::path& dir = scratch_with_trees();
  write_text(dir / "slide.json", sliding_scene(/*frames=*/5).dump());
  const std::string scene = (dir / "slide.json").string();
  for (const std::string& args : std::vector<std::string>{
           "run", "run " + scene + " --lod best", "run " + scene + " --bogus",
           "run " + scene + " --min-depth 3 --max-depth 2", "frobnicate", "gen --static 1 --moving 1 --seed 1"})
    EXPECT_EQ(run_command(kOctscene + " " + args, dir).status, 2) << args;
  EXPECT_EQ(run_command(kOctscene + " run --help", dir).status, 0);
}

// The library call reports the same collisions the log shows, and the poses
// of the tested frame when asked.
TEST(Run, RunSceneReportsFramesAndPoses) {
  const fs::path& dir = scratch_with_trees();
  Result<Scene> scene = parse_scene(sliding_scene(/*frames=*/80).dump(), dir.string());
  ASSERT_TRUE(scene) << scene.error().message;
  Result<ModelLibrary> library = ModelLibrary::open(scene->baked);
  ASSERT_TRUE(library) << library.error().message;
  RunOptions options;
  options.lod.policy = LodPolicy::fixed;
  options.lod.max_depth = 2;
  options.response = Response::none;
  options.report_poses = true;
  int64_t frames_seen = 0;
  uint64_t collisions = 0;
  Result<RunResult> r = run_scene(*scene, *library, options, [&](const FrameReport& f) {
    EXPECT_EQ(f.frame, frames_seen++);
    ASSERT_EQ(f.poses.size(), 3u);
    EXPECT_NEAR(f.poses[1].position.x(), -6 + 0.1 * static_cast<double>(f.frame), 1e-9);
    for (const Collision& c : f.collisions) {
      EXPECT_EQ(c.depth_a, 2);
      EXPECT_EQ(c.depth_b, 2);
      EXPECT_EQ(c.position_b, f.poses[c.b].position);
    }
    collisions += f.collisions.size();
  });
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(frames_seen, 80);
  EXPECT_EQ(r->frames, 80);
  EXPECT_EQ(r->collisions, collisions);
  EXPECT_EQ(r->depth_pairs.size(), 1u);
  EXPECT_EQ((r->depth_pairs[{2, 2}]), collisions);
  EXPECT_GE(collisions, 35u);  // frames 41..79 at least
}

// Trees are decoded only as deep as the LOD can reach.
TEST(Run, LoadsOnlyTheDepthTheLodReaches) {
  const fs::path& dir = scratch_with_trees();
  Result<Scene> scene = parse_scene(sliding_scene(/*frames=*/1).dump(), dir.string());
  ASSERT_TRUE(scene);
  for (int depth : {0, 2, 4, 9}) {
    Result<ModelLibrary> library = ModelLibrary::open(scene->baked);
    ASSERT_TRUE(library);
    Result<SceneModels> models = load_scene_models(*scene, *library, depth);
    ASSERT_TRUE(models) << models.error().message;
    ASSERT_EQ(models->trees.size(), 2u);  // cube once, slab once
    EXPECT_EQ(models->tree_of_object, (std::vector<uint32_t>{0, 0, 1}));
    for (const ObjectTree& t : models->trees) EXPECT_EQ(t.loaded_depth(), std::min(depth, 4));
  }
}

}  // namespace
}  // namespace octbake::scene
