// The scenes shipped in assets/scenes/ stay valid: they parse, have the
// thesis's object counts (or the stress properties they were made for), name
// only bundled models, are what the commands in their README generate, and
// log the same bytes for every thread count.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "helpers.h"
#include "run.h"
#include "scene.h"

namespace octbake::scene {
namespace {

using namespace octbake::scene::testing;

const fs::path kRoot = OCTBAKE_SOURCE_DIR;
const char* const kModels[] = {"tree", "human", "frustum", "elephant", "car"};

#if defined(__SANITIZE_ADDRESS__) || !defined(NDEBUG)
constexpr int64_t kThreadFrames = 40;  // sanitizer and debug builds are slow
#else
constexpr int64_t kThreadFrames = 300;
#endif

struct Expected {
  const char* file;
  size_t statics, moving;
};

class BundledScene : public ::testing::TestWithParam<Expected> {};

TEST_P(BundledScene, ParsesWithTheThesisCounts) {
  const Expected want = GetParam();
  Result<Scene> scene = load_scene((kRoot / "assets/scenes" / want.file).string());
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  EXPECT_EQ(scene->frames, 7200);  // 240 s at 30 frames a second
  EXPECT_NEAR(scene->timestep, 1.0 / 30.0, 1e-9);
  size_t moving = 0;
  for (const SceneObject& o : scene->objects) {
    moving += o.velocity != Eigen::Vector3d::Zero();
    EXPECT_TRUE(fs::exists(kRoot / "assets" / (o.model + ".obj"))) << o.name << ": " << o.model;
  }
  EXPECT_EQ(scene->objects.size() - moving, want.statics);
  EXPECT_EQ(moving, want.moving);
}

INSTANTIATE_TEST_SUITE_P(Thesis, BundledScene,
                         ::testing::Values(Expected{"test1.json", 100, 50}, Expected{"test2.json", 140, 70}));

Scene load_bundled(const char* file) {
  Result<Scene> scene = load_scene((kRoot / "assets/scenes" / file).string());
  EXPECT_TRUE(scene.ok()) << file << ": " << scene.error().message;
  return scene ? *scene : Scene{};
}

TEST(BundledStress, ScalesSpanOver400x) {
  const Scene s = load_bundled("scales.json");
  ASSERT_FALSE(s.objects.empty());
  double lo = 1e300, hi = 0;
  for (const SceneObject& o : s.objects) lo = std::min(lo, o.pose.scale), hi = std::max(hi, o.pose.scale);
  EXPECT_GE(hi / lo, 400 * 0.9) << lo << " .. " << hi;  // log-uniform over 0.05..20: the extremes come close
  EXPECT_LE(s.frames, 900);  // `octscene trade` on it stays well under a minute
}

TEST(BundledStress, FlythroughEveryObjectRotatedAShareSpinningCameraOnAPath) {
  const Scene s = load_bundled("flythrough.json");
  ASSERT_FALSE(s.objects.empty());
  size_t spinning = 0;
  for (const SceneObject& o : s.objects) {
    EXPECT_GT(std::abs(o.pose.rotation.x()) + std::abs(o.pose.rotation.z()), 1e-6) << o.name << " is not rotated";
    spinning += !o.angular_velocity.isZero(0);
  }
  EXPECT_GT(spinning, s.objects.size() * 3 / 10);
  EXPECT_LT(spinning, s.objects.size() * 7 / 10);
  ASSERT_GE(s.camera_path.size(), 2u);
  EXPECT_EQ(s.camera_path.front().frame, 0);
  EXPECT_EQ(s.camera_path.back().frame, s.frames);
  // The camera flies inside the world box, through the crowd.
  for (const CameraKey& k : s.camera_path)
    EXPECT_TRUE((k.position.array() > s.world.min.array()).all() && (k.position.array() < s.world.max.array()).all());
  EXPECT_LE(s.frames, 900);
}

// The five bundled models baked once into a scratch folder (depth 4 keeps it
// quick; generation reads only their bounds).
const fs::path& baked_assets() {
  static const fs::path dir = [] {
    const fs::path d = scratch_with_trees() / "assets_baked";
    std::string command = std::string(OCTBAKE_BIN) + " -q -d 4 -o " + d.string();
    for (const char* m : kModels) command += " " + (kRoot / "assets" / (std::string(m) + ".obj")).string();
    Command c = run_command(command, scratch_with_trees());
    EXPECT_EQ(c.status, 0) << c.err;
    return d;
  }();
  return dir;
}

// Most statics lean on another static (their world boxes overlap at frame
// 0), no moving object touches anything, and the camera flies: the pairs
// that coherence answers from last frame, among pairs it must test.
TEST(BundledStress, ClutterStaticsRestOnStatics) {
  const Scene s = load_bundled("clutter.json");
  ASSERT_FALSE(s.objects.empty());
  Result<ModelLibrary> library = ModelLibrary::open(baked_assets().string());
  ASSERT_TRUE(library) << library.error().message;
  std::vector<Aabb> boxes;
  for (const SceneObject& o : s.objects) boxes.push_back(world_bounds(place(library->info(o.model)->bounds, o.pose)));
  const auto overlap = [](const Aabb& a, const Aabb& b) {
    return (a.min.array() <= b.max.array()).all() && (b.min.array() <= a.max.array()).all();
  };
  size_t statics = 0, resting = 0;
  for (size_t i = 0; i < s.objects.size(); ++i) {
    const bool moving = !s.objects[i].velocity.isZero(0);
    statics += !moving;
    size_t met = 0;
    for (size_t j = 0; j < boxes.size(); ++j) met += j != i && overlap(boxes[i], boxes[j]);
    if (moving) {
      EXPECT_EQ(met, 0u) << s.objects[i].name << " moves and starts in contact";
    }
    bool leans = false;
    for (size_t j = 0; j < i; ++j) leans = leans || overlap(boxes[i], boxes[j]);
    resting += !moving && leans;
  }
  EXPECT_GT(resting, statics / 2);
  EXPECT_GE(s.camera_path.size(), 2u);
  EXPECT_LE(s.frames, 900);
}

// Every `octscene gen ARGS > assets/scenes/X.json` in the README, joined over
// its line continuations (no <regex>: GCC 12 warns inside it at -O1).
std::vector<std::pair<std::string, std::string>> readme_commands() {
  const std::string raw = read_text(kRoot / "assets/scenes/README.md");
  std::string text;
  for (size_t i = 0; i < raw.size(); ++i) {
    if (raw[i] == '\\' && i + 1 < raw.size() && raw[i + 1] == '\n') {
      size_t next = i + 2;  // skip the break and the next line's indent
      while (next < raw.size() && raw[next] == ' ') ++next;
      i = next - 1;
      continue;
    }
    text += raw[i];
  }
  std::vector<std::pair<std::string, std::string>> out;
  const std::string start = "octscene gen ", target = "> assets/scenes/";
  for (size_t at = text.find(start); at != std::string::npos; at = text.find(start, at + 1)) {
    const size_t end = text.find('\n', at), to = text.find(target, at);
    if (to == std::string::npos || to > end) continue;
    const size_t name = to + target.size();
    out.emplace_back(text.substr(at + start.size(), to - at - start.size()), text.substr(name, end - name));
  }
  return out;
}

TEST(BundledScenes, ReadmeCommandsGenerateTheShippedBytes) {
  const auto commands = readme_commands();
  ASSERT_GE(commands.size(), 4u);
  for (const auto& [args, file] : commands) {
    std::string a = args;
    const std::string from = "--baked baked ";
    ASSERT_NE(a.find(from), std::string::npos) << file << ": " << a;
    a.replace(a.find(from), from.size(), "--baked " + baked_assets().string() + " ");
    Command g = run_command(std::string(OCTSCENE_BIN) + " gen " + a, scratch_with_trees());
    ASSERT_EQ(g.status, 0) << file << ": " << g.err;
    EXPECT_TRUE(g.out == read_text(kRoot / "assets/scenes" / file)) << file << " is not what its README command writes";
  }
}

// Collisions, logs and counts are the same for every thread count.
TEST(BundledScenes, LogsAreByteIdenticalForEveryThreadCount) {
  Result<ModelLibrary> library = ModelLibrary::open(baked_assets().string());
  ASSERT_TRUE(library) << library.error().message;
  for (const char* file : {"test1.json", "test2.json", "scales.json", "flythrough.json", "clutter.json"}) {
    Scene scene = load_bundled(file);
    Result<SceneModels> models = load_scene_models(scene, *library, 12);
    ASSERT_TRUE(models) << models.error().message;
    std::string first_log;
    RunResult first;
    for (int threads : {1, 2, 3, 8}) {
      RunOptions options;  // the defaults of `octscene run`: screen LOD, separate
      options.frames = kThreadFrames;
      options.threads = threads;
      std::string log;
      Result<RunResult> r = run_scene(scene, *models, options, [&](const FrameReport& f) {
        append_log_lines(scene, f, log);
      });
      ASSERT_TRUE(r) << r.error().message;
      if (threads == 1) {
        first_log = log, first = *r;
        continue;
      }
      EXPECT_TRUE(log == first_log) << file << ": --threads " << threads << " logs other collisions";
      EXPECT_EQ(r->collisions, first.collisions) << file << ", threads " << threads;
      EXPECT_EQ(r->pair_tests, first.pair_tests) << file << ", threads " << threads;
      EXPECT_EQ(r->box_tests, first.box_tests) << file << ", threads " << threads;
      EXPECT_EQ(r->depth_pairs, first.depth_pairs) << file << ", threads " << threads;
    }
    EXPECT_GT(first.pair_tests, 0u) << file;
  }
}

// The log's columns up to box_tests (frame, time, a, b, depth_a, depth_b,
// box_tests): what does not scale with the scene.
std::string unscaled_columns(const std::string& log) {
  std::string out;
  size_t start = 0;
  while (start < log.size()) {
    const size_t end = log.find('\n', start);
    const std::string line = log.substr(start, end - start);
    size_t cut = 0;
    for (int commas = 0; commas < 7 && cut != std::string::npos; ++commas) cut = line.find(',', cut + (commas > 0));
    out += line.substr(0, cut) + '\n';
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return out;
}

// A scene scaled by a power of two (every position, velocity and object
// scale, the camera, its path, near and far, the world box) is the same
// scene: the same collisions at the same depths after the same box tests,
// through the scene file too, down to 2^-1000 and up to 2^1000, where
// squared lengths under- or overflow (a camera's view direction and pixel
// areas once went to zero there).
TEST(BundledScenes, ScaleFreeAtTheExtremesOfDouble) {
  Result<ModelLibrary> library = ModelLibrary::open(baked_assets().string());
  ASSERT_TRUE(library) << library.error().message;
  for (const char* file : {"test1.json", "scales.json", "flythrough.json"}) {
    const Scene scene = load_bundled(file);
    Result<SceneModels> models = load_scene_models(scene, *library, 12);
    ASSERT_TRUE(models) << models.error().message;
    std::string first_log;
    RunResult first;
    for (const int e : {0, -1000, -600, 600, 1000}) {
      const double k = std::ldexp(1.0, e);
      Scene scaled = scene;
      scaled.camera.position *= k, scaled.camera.look_at *= k;
      scaled.camera.near_plane *= k, scaled.camera.far_plane *= k;
      for (CameraKey& key : scaled.camera_path) key.position *= k, key.look_at *= k;
      scaled.world.min *= k, scaled.world.max *= k;
      for (SceneObject& o : scaled.objects) o.pose.position *= k, o.pose.scale *= k, o.velocity *= k;
      Result<Scene> parsed = parse_scene(write_scene(scaled, scene.baked), "");
      ASSERT_TRUE(parsed) << file << ", 2^" << e << ": " << parsed.error().message;
      RunOptions options;  // the defaults of `octscene run`: screen LOD, separate
      options.frames = 100;  // scales.json's first contact is at frame 62 (sanitizer builds too)
      std::string log;
      Result<RunResult> r = run_scene(*parsed, *models, options, [&](const FrameReport& f) {
        append_log_lines(*parsed, f, log);
      });
      ASSERT_TRUE(r) << file << ", 2^" << e << ": " << r.error().message;
      if (e == 0) {
        first_log = unscaled_columns(log), first = *r;
        continue;
      }
      EXPECT_TRUE(unscaled_columns(log) == first_log) << file << ": scaled by 2^" << e << ", other collisions";
      EXPECT_EQ(r->collisions, first.collisions) << file << ", 2^" << e;
      EXPECT_EQ(r->box_tests, first.box_tests) << file << ", 2^" << e;
      EXPECT_EQ(r->depth_pairs, first.depth_pairs) << file << ", 2^" << e;
    }
    EXPECT_GT(first.collisions, 0u) << file;
  }
}

}  // namespace
}  // namespace octbake::scene
