// The frame loop behind `octscene run` (docs/interface.md sections 5 and 6), as a
// library call so other subcommands (`octscene trade`) can run a scene under
// many settings and see every frame's reported pairs.
#pragma once
#include <cstdint>
#include <functional>
#include <map>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "octbake/baked_file.h"
#include "octbake/result.h"
#include "octbake/world.h"
#include "scene.h"

namespace octbake::scene {

struct RunOptions {
  // lod.max_depth is clamped per tree to its baked depth, so the default (12)
  // means "each tree's baked depth".
  LodSettings lod;
  Response response = Response::separate;
  int64_t frames = -1;  // < 0: the scene's frame count
  bool areas_every_frame = false;
  // Fill FrameReport::poses (costs a copy of every pose per frame).
  bool report_poses = false;
  // Worker threads for World::step() (>= 1). Collisions, logs and counts are
  // the same for every value; `octscene run` defaults to all cores.
  int threads = 1;
};

// One stepped frame, handed to the callback right after World::step().
struct FrameReport {
  int64_t frame = 0;
  double time = 0;  // frame * timestep
  // This frame's collisions, sorted by (a, b); indices into Scene::objects.
  std::span<const Collision> collisions;
  FrameStats stats;
  double ms = 0;  // wall time of World::step() alone
  // Every object's pose at the tested frame (before the response and the
  // advance); empty unless RunOptions::report_poses.
  std::span<const Pose> poses;
  const World* world = nullptr;  // state after the step (next frame's poses)
};

struct RunResult {
  int64_t frames = 0;
  uint64_t collisions = 0;
  uint64_t pair_tests = 0;
  uint64_t pairs_reused = 0;  // pair tests answered by last frame's result (0 box tests)
  uint64_t pairs_kept_apart = 0;  // misses answered by their separation (0 box tests)
  uint64_t box_tests = 0;          // summed over pair tests
  uint64_t collision_box_tests = 0;  // summed over reported collisions only
  // Collisions per depth pair, key (lo, hi) with lo <= hi.
  std::map<std::pair<int, int>, uint64_t> depth_pairs;
  double load_ms = 0;  // decoding the trees (0 when given preloaded models)
  double run_ms = 0;   // whole loop, callback included
  double frame_ms_mean = 0, frame_ms_p99 = 0;  // World::step() alone
};

// The trees a scene names, each decoded once; objects index into `trees`.
struct SceneModels {
  std::vector<std::string> names;
  std::vector<ObjectTree> trees;
  std::vector<uint32_t> tree_of_object;  // per Scene::objects entry
  double load_ms = 0;
};

// Checks that every object's model exists (error "objects[3].model: no tree
// \"cat\" in baked/"), then loads each named tree once, down to
// min(depth, its baked depth) and no deeper.
Result<SceneModels> load_scene_models(const Scene& scene, ModelLibrary& library, int depth);

// Runs with preloaded trees (loaded at least as deep as options.lod.max_depth
// to be exact; deeper levels are simply not used). `on_frame` may be empty.
Result<RunResult> run_scene(const Scene& scene, const SceneModels& models, const RunOptions& options,
                            const std::function<void(const FrameReport&)>& on_frame);

// Loads what options.lod.max_depth can reach, then runs.
Result<RunResult> run_scene(const Scene& scene, ModelLibrary& library, const RunOptions& options,
                            const std::function<void(const FrameReport&)>& on_frame);

// The collision log (docs/interface.md section 6).
constexpr const char* kLogHeader = "frame,time,a,b,depth_a,depth_b,box_tests,ax,ay,az,bx,by,bz";
// Appends one log line (with '\n') per collision; numbers round-trip and do not
// depend on the locale.
void append_log_lines(const Scene& scene, const FrameReport& frame, std::string& out);

}  // namespace octbake::scene
