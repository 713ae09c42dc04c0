// `octscene plan` and `octbake --for-scene`, checked against runs on fully
// baked files: a run on trees cut to the planned depths gives the same log,
// and the planned bytes are what the loader decodes.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "helpers.h"
#include "octbake/baked_file.h"
#include "plan.h"
#include "run.h"
#include "scene.h"

namespace octbake::scene {
namespace {

using namespace octbake::scene::testing;
using nlohmann::json;

const std::string kOctscene = OCTSCENE_BIN;
const std::string kOctbake = OCTBAKE_BIN;
#if defined(__SANITIZE_ADDRESS__)
constexpr int kFrames = 150;  // sanitizer builds are slow
#else
constexpr int kFrames = 900;
#endif

// The bundled models baked to depth 5 in a scratch folder (once per process).
const fs::path& full_dir() {
  static const fs::path dir = [] {
    const fs::path d = scratch_with_trees() / "assets_full";
    const fs::path assets = fs::path(OCTBAKE_SOURCE_DIR) / "assets";
    std::string cmd = kOctbake + " -q -d 5 -o " + d.string();
    for (const char* m : {"car", "elephant", "frustum", "human", "tree"}) cmd += " " + (assets / m).string() + ".obj";
    Command c = run_command(cmd, scratch_with_trees());
    if (c.status != 0) ADD_FAILURE() << c.err;
    return d;
  }();
  return dir;
}

// The thesis's test 1 scene seen from further away (so the screen LOD stops
// short of the baked depth for most models), shortened, on `baked`.
json far_scene(const fs::path& baked, bool drop_tree = false) {
  json j = json::parse(read_text(fs::path(OCTBAKE_SOURCE_DIR) / "assets/scenes/test1.json"));
  j["baked"] = baked.string();
  j["frames"] = kFrames;
  j["camera"]["position"] = {40, 90, -300};
  if (drop_tree) {
    json kept = json::array();
    for (const json& o : j["objects"])
      if (o["model"] != "tree") kept.push_back(o);
    j["objects"] = kept;
  }
  return j;
}

std::string log_of(const Scene& scene, const SceneModels& models, const RunOptions& options) {
  std::string log;
  Result<RunResult> r = run_scene(scene, models, options, [&](const FrameReport& f) { append_log_lines(scene, f, log); });
  EXPECT_TRUE(r) << r.error().message;
  return log;
}

// Every model loaded to its own depth (the plan's), as a reduced file would.
SceneModels cut_to(const SceneModels& full, ModelLibrary& library, const ScenePlan& plan) {
  SceneModels cut;
  cut.names = full.names;
  cut.tree_of_object = full.tree_of_object;
  for (size_t t = 0; t < full.names.size(); ++t) {
    Result<ObjectTree> tree = library.load(full.names[t], plan.models[t].needed);
    EXPECT_TRUE(tree) << tree.error().message;
    cut.trees.push_back(std::move(tree).value());
  }
  return cut;
}

struct Setting {
  LodPolicy policy;
  int min_depth, max_depth;
  double tolerance;
  Response response;
};

class PlanSetting : public ::testing::TestWithParam<Setting> {};

// The property that makes the plan useful: runs on trees cut to the planned
// depths log exactly what runs on the full trees log.
TEST_P(PlanSetting, TreesCutToThePlanGiveTheSameLog) {
  const Setting s = GetParam();
  Result<Scene> scene = parse_scene(far_scene(full_dir()).dump(), "/");
  ASSERT_TRUE(scene) << scene.error().message;
  RunOptions options;
  options.lod = {s.policy, s.min_depth, s.max_depth, s.tolerance};
  options.response = s.response;
  Result<ModelLibrary> library = ModelLibrary::open(scene->baked);
  ASSERT_TRUE(library);
  Result<SceneModels> full = load_scene_models(*scene, *library, s.max_depth);
  ASSERT_TRUE(full) << full.error().message;
  Result<ScenePlan> plan = plan_scene(*scene, *full, options);
  ASSERT_TRUE(plan) << plan.error().message;
  ASSERT_EQ(plan->models.size(), 5u);
  EXPECT_EQ(plan->frames, kFrames);

  const std::string full_log = log_of(*scene, *full, options);
  EXPECT_FALSE(full_log.empty());  // contacts happen, so responses shape the motion
  EXPECT_EQ(log_of(*scene, cut_to(*full, *library, *plan), options), full_log);

  for (const ModelPlan& m : plan->models) {
    EXPECT_EQ(m.baked_depth, 5);
    EXPECT_EQ(m.lod_top, std::min(5, s.max_depth));
    EXPECT_GE(m.deepest, std::min(s.min_depth, m.lod_top));
    EXPECT_LE(m.deepest, m.lod_top);
    EXPECT_EQ(m.needed, s.policy == LodPolicy::thesis ? m.lod_top : m.deepest);
    EXPECT_EQ(m.reaches_baked(), m.needed == 5);
    // The planned bytes are what the loader decodes for that depth.
    Result<ModelLibrary> fresh = ModelLibrary::open(scene->baked);
    ASSERT_TRUE(fresh);
    ASSERT_TRUE(fresh->load(m.model, m.needed));
    EXPECT_EQ(fresh->stats().bytes_decompressed, m.bytes_needed) << m.model;
    EXPECT_LE(m.bytes_needed, m.bytes_loaded);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Settings, PlanSetting,
    ::testing::Values(Setting{LodPolicy::screen, 1, 12, 1.0, Response::separate},
                      Setting{LodPolicy::screen, 1, 12, 4.0, Response::thesis},
                      Setting{LodPolicy::screen, 2, 4, 0.5, Response::separate},
                      Setting{LodPolicy::thesis, 1, 3, 1.0, Response::thesis},
                      Setting{LodPolicy::fixed, 1, 3, 1.0, Response::separate}));

// Not vacuous: from afar the screen LOD stops short of the baked depth for
// some models, and the plan is tight (a shallower cut changes a depth).
TEST(Plan, FromAfarSomeModelsNeedLessThanTheBakedDepth) {
  Result<Scene> scene = parse_scene(far_scene(full_dir()).dump(), "/");
  ASSERT_TRUE(scene);
  Result<ModelLibrary> library = ModelLibrary::open(scene->baked);
  ASSERT_TRUE(library);
  Result<SceneModels> full = load_scene_models(*scene, *library, 12);
  ASSERT_TRUE(full);
  RunOptions options;
  Result<ScenePlan> plan = plan_scene(*scene, *full, options);
  ASSERT_TRUE(plan);
  int reduced = 0;
  for (const ModelPlan& m : plan->models) reduced += m.needed < m.baked_depth;
  EXPECT_GE(reduced, 2);
  // Tight: some object of each model is picked at exactly its needed depth.
  std::vector<int> seen(full->names.size(), 0);
  ASSERT_TRUE(run_scene(*scene, *full, options, [&](const FrameReport& f) {
    for (size_t i = 0; i < f.world->size(); ++i) {
      const uint32_t t = full->tree_of_object[i];
      seen[t] = std::max(seen[t], f.world->depth(i));
    }
  }));
  for (size_t t = 0; t < seen.size(); ++t) EXPECT_EQ(seen[t], plan->models[t].deepest);
}

TEST(Plan, ZeroFramesNeedsNothing) {
  Result<Scene> scene = parse_scene(far_scene(full_dir()).dump(), "/");
  ASSERT_TRUE(scene);
  Result<ModelLibrary> library = ModelLibrary::open(scene->baked);
  ASSERT_TRUE(library);
  Result<SceneModels> full = load_scene_models(*scene, *library, 12);
  ASSERT_TRUE(full);
  RunOptions options;
  options.frames = 0;
  options.lod.policy = LodPolicy::thesis;
  Result<ScenePlan> plan = plan_scene(*scene, *full, options);
  ASSERT_TRUE(plan);
  for (const ModelPlan& m : plan->models) {
    EXPECT_EQ(m.needed, 0);
    EXPECT_EQ(m.bytes_needed, 0u);
  }
}

// The command prints what the library call computes.
TEST(Plan, JsonCommandMatchesTheLibraryCall) {
  const fs::path dir = scratch_with_trees();
  write_text(dir / "far.json", far_scene(full_dir()).dump());
  Command c = run_command(kOctscene + " plan " + (dir / "far.json").string() + " --pixel-tolerance 2 --json", dir);
  ASSERT_EQ(c.status, 0) << c.err;
  const json out = json::parse(c.out);
  EXPECT_EQ(out["format"], "octscene-plan");
  ASSERT_EQ(out["scenes"].size(), 1u);
  const json& models = out["scenes"][0]["models"];

  Result<Scene> scene = load_scene((dir / "far.json").string());
  ASSERT_TRUE(scene);
  Result<ModelLibrary> library = ModelLibrary::open(scene->baked);
  ASSERT_TRUE(library);
  Result<SceneModels> full = load_scene_models(*scene, *library, 12);
  ASSERT_TRUE(full);
  RunOptions options;
  options.lod.pixel_tolerance = 2;
  Result<ScenePlan> plan = plan_scene(*scene, *full, options);
  ASSERT_TRUE(plan);
  ASSERT_EQ(models.size(), plan->models.size());
  for (size_t i = 0; i < models.size(); ++i) {
    EXPECT_EQ(models[i]["model"], plan->models[i].model);
    EXPECT_EQ(models[i]["deepest"], plan->models[i].deepest);
    EXPECT_EQ(models[i]["needed"], plan->models[i].needed);
    EXPECT_EQ(models[i]["bytes_needed"], plan->models[i].bytes_needed);
    EXPECT_EQ(models[i]["reaches_baked_depth"], plan->models[i].reaches_baked());
  }
  // The table names each model and says when the bake stopped the LOD.
  c = run_command(kOctscene + " plan " + (dir / "far.json").string() + " --lod fixed", dir);
  ASSERT_EQ(c.status, 0) << c.err;
  EXPECT_NE(c.out.find("elephant"), std::string::npos);
  EXPECT_NE(c.out.find("reaches the baked depth"), std::string::npos);
}

// octbake --for-scene: only the named models, each at its planned depth, and
// the scene's run on the reduced files logs what it logs on the full ones.
TEST(ForScene, ReducedFilesGiveTheSameLogAsFullOnes) {
  const fs::path dir = scratch_with_trees() / "for_scene";
  fs::create_directories(dir);
  write_text(dir / "far.json", far_scene(full_dir(), /*drop_tree=*/true).dump());
  const fs::path assets = fs::path(OCTBAKE_SOURCE_DIR) / "assets";
  std::string inputs;
  for (const char* m : {"car", "elephant", "frustum", "human", "tree"}) inputs += " " + (assets / m).string() + ".obj";
  Command c = run_command(kOctbake + " -q -d 5 --for-scene " + (dir / "far.json").string() + " -o " +
                              (dir / "reduced").string() + inputs,
                          dir);
  ASSERT_EQ(c.status, 0) << c.err;
  EXPECT_NE(c.err.find("octbake: note: " + (assets / "tree.obj").string() + ": skipped"), std::string::npos) << c.err;
  EXPECT_FALSE(fs::exists(dir / "reduced" / "tree.oct"));

  // Each file holds exactly the planned depth.
  Result<Scene> scene = load_scene((dir / "far.json").string());
  ASSERT_TRUE(scene);
  Result<ModelLibrary> library = ModelLibrary::open(scene->baked);
  ASSERT_TRUE(library);
  Result<SceneModels> full = load_scene_models(*scene, *library, 12);
  ASSERT_TRUE(full);
  Result<ScenePlan> plan = plan_scene(*scene, *full, RunOptions{});
  ASSERT_TRUE(plan);
  int reduced = 0;
  for (const ModelPlan& m : plan->models) {
    Result<BakedFile> file = BakedFile::open((dir / "reduced" / (m.model + ".oct")).string());
    ASSERT_TRUE(file) << m.model << ": " << file.error().message;
    EXPECT_EQ(file->trees()[0].depth, std::max(1, m.needed)) << m.model;
    reduced += m.needed < 5;
  }
  EXPECT_GE(reduced, 2);

  const std::string scene_path = (dir / "far.json").string();
  c = run_command(kOctscene + " run " + scene_path + " --log " + (dir / "full.csv").string(), dir);
  ASSERT_EQ(c.status, 0) << c.err;
  c = run_command(kOctscene + " run " + scene_path + " --baked " + (dir / "reduced").string() + " --log " +
                      (dir / "reduced.csv").string(),
                  dir);
  ASSERT_EQ(c.status, 0) << c.err;
  const std::string full_log = read_text(dir / "full.csv");
  EXPECT_GT(std::count(full_log.begin(), full_log.end(), '\n'), 3);  // header + collisions (6 in 150 frames)
  EXPECT_EQ(read_text(dir / "reduced.csv"), full_log);
}

TEST(ForScene, ErrorsNameThePathAndTheReason) {
  const fs::path dir = scratch_with_trees() / "for_scene_errors";
  fs::create_directories(dir);
  write_text(dir / "far.json", far_scene(full_dir()).dump());
  const fs::path assets = fs::path(OCTBAKE_SOURCE_DIR) / "assets";
  const std::string scene = (dir / "far.json").string();
  // The scene names "tree", which no input provides.
  Command c = run_command(kOctbake + " -q --for-scene " + scene + " -o " + (dir / "out").string() + " " +
                              (assets / "car.obj").string(),
                          dir);
  EXPECT_EQ(c.status, 1);
  EXPECT_NE(c.err.find("octbake: error: " + scene + ": objects["), std::string::npos) << c.err;
  EXPECT_NE(c.err.find("no input file provides model \"tree\""), std::string::npos) << c.err;
  // The scene cannot be planned, but the inputs that bake are still baked,
  // to the full depth (-d), each with a note.
  EXPECT_NE(c.err.find("octbake: note: " + (assets / "car.obj").string() + ": to depth 6: "), std::string::npos)
      << c.err;
  auto car = BakedFile::open((dir / "out" / "car.oct").string());
  ASSERT_TRUE(car.ok()) << c.err;
  EXPECT_EQ(car->trees()[0].depth, 6);
  // The same when an input fails to bake, and (without -q) the run ends with
  // one summary line counting both.
  write_text(dir / "tree.obj", "garbage\n");
  fs::remove_all(dir / "out");
  c = run_command(kOctbake + " --for-scene " + scene + " -o " + (dir / "out").string() + " " +
                      (assets / "car.obj").string() + " " + (dir / "tree.obj").string(),
                  dir);
  EXPECT_EQ(c.status, 1);
  EXPECT_NE(c.err.find("octbake: error: " + (dir / "tree.obj").string() + ": "), std::string::npos) << c.err;
  EXPECT_TRUE(fs::exists(dir / "out" / "car.oct")) << c.err;
  EXPECT_FALSE(fs::exists(dir / "out" / "tree.oct")) << c.err;
  EXPECT_NE(c.err.find("octbake: 1 baked, 0 up to date, 1 failed"), std::string::npos) << c.err;
  // A bad scene.
  write_text(dir / "bad.json", "{\"format\": 3}");
  c = run_command(kOctbake + " -q --for-scene " + (dir / "bad.json").string() + " " + (assets / "car.obj").string(), dir);
  EXPECT_EQ(c.status, 1);
  EXPECT_EQ(c.err.rfind("octbake: error: " + (dir / "bad.json").string() + ": ", 0), 0u) << c.err;
  // --pack cannot hold one depth per model.
  c = run_command(kOctbake + " -q --for-scene " + scene + " --pack " + (dir / "p.oct").string() + " " +
                      (assets / "car.obj").string(),
                  dir);
  EXPECT_EQ(c.status, 2);
  EXPECT_EQ(c.err.rfind("octbake: error: --for-scene", 0), 0u) << c.err;
}

}  // namespace
}  // namespace octbake::scene
