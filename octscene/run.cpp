#include "run.h"

#include <algorithm>
#include <charconv>
#include <chrono>

namespace octbake::scene {
namespace {

using Clock = std::chrono::steady_clock;

double ms_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// Shortest text that reads back to the same double; never locale dependent.
void append_number(std::string& out, double v) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

template <class Int>
void append_int(std::string& out, Int v) {
  char buf[24];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

}  // namespace

Result<SceneModels> load_scene_models(const Scene& scene, ModelLibrary& library, int depth) {
  auto start = Clock::now();
  SceneModels models;
  // Every name is checked before any level is decoded: a typo fails fast.
  std::vector<int> load_depth;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const std::string& model = scene.objects[i].model;
    auto it = std::find(models.names.begin(), models.names.end(), model);
    if (it == models.names.end()) {
      Result<TreeInfo> info = library.info(model);
      if (!info) {
        std::string path = "objects[" + std::to_string(i) + "].model";
        if (info.error().code == ErrorCode::not_found)
          return Error{ErrorCode::not_found, path + ": no tree \"" + model + "\" in " + scene.baked};
        return Error{info.error().code, path + ": " + info.error().message};
      }
      models.names.push_back(model);
      load_depth.push_back(std::clamp(depth, 0, info->depth));
      it = models.names.end() - 1;
    }
    models.tree_of_object.push_back(static_cast<uint32_t>(it - models.names.begin()));
  }
  for (size_t t = 0; t < models.names.size(); ++t) {
    Result<ObjectTree> tree = library.load(models.names[t], load_depth[t]);
    if (!tree) return Error{tree.error().code, "model \"" + models.names[t] + "\": " + tree.error().message};
    models.trees.push_back(std::move(tree).value());
  }
  models.load_ms = ms_between(start, Clock::now());
  return models;
}

Result<RunResult> run_scene(const Scene& scene, const SceneModels& models, const RunOptions& options,
                            const std::function<void(const FrameReport&)>& on_frame) {
  if (models.tree_of_object.size() != scene.objects.size() || models.trees.size() != models.names.size())
    return Error{ErrorCode::invalid_argument, "models were loaded for another scene"};
  if (options.lod.min_depth < 0 || options.lod.max_depth < options.lod.min_depth)
    return Error{ErrorCode::invalid_argument, "need 0 <= min depth <= max depth"};
  if (options.threads < 1) return Error{ErrorCode::invalid_argument, "threads: must be >= 1"};

  WorldSettings settings;
  settings.bounds = scene.world;
  settings.world_depth = scene.world_depth;
  settings.timestep = scene.timestep;
  settings.response = options.response;
  settings.lod = options.lod;
  settings.camera = scene.camera;
  settings.areas_every_frame = options.areas_every_frame;
  settings.camera_path = scene.camera_path;
  settings.threads = options.threads;

  std::vector<ObjectDesc> descs;
  descs.reserve(scene.objects.size());
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& o = scene.objects[i];
    descs.push_back({o.name, &models.trees[models.tree_of_object[i]], o.pose, o.velocity, o.angular_velocity});
  }

  auto run_start = Clock::now();
  World world(settings, std::move(descs));
  const int64_t frames = options.frames >= 0 ? options.frames : scene.frames;

  RunResult result;
  result.load_ms = models.load_ms;
  std::vector<double> frame_ms;
  frame_ms.reserve(static_cast<size_t>(frames));
  std::vector<Collision> collisions;
  std::vector<Pose> poses;
  for (int64_t f = 0; f < frames; ++f) {
    if (options.report_poses) {
      poses.resize(world.size());
      for (size_t i = 0; i < world.size(); ++i) poses[i] = world.object(i).pose;
    }
    collisions.clear();
    auto t0 = Clock::now();
    FrameStats stats = world.step(collisions);
    double ms = ms_between(t0, Clock::now());
    frame_ms.push_back(ms);

    result.pair_tests += stats.pair_tests;
    result.pairs_reused += stats.pairs_reused;
    result.pairs_kept_apart += stats.pairs_kept_apart;
    result.box_tests += stats.box_tests;
    result.collisions += collisions.size();
    for (const Collision& c : collisions) {
      result.collision_box_tests += c.box_tests;
      ++result.depth_pairs[{std::min(c.depth_a, c.depth_b), std::max(c.depth_a, c.depth_b)}];
    }
    if (on_frame) {
      FrameReport report;
      report.frame = f;
      report.time = static_cast<double>(f) * scene.timestep;
      report.collisions = collisions;
      report.stats = stats;
      report.ms = ms;
      report.poses = poses;
      report.world = &world;
      on_frame(report);
    }
  }
  result.frames = frames;
  result.run_ms = ms_between(run_start, Clock::now());
  if (!frame_ms.empty()) {
    double sum = 0;
    for (double ms : frame_ms) sum += ms;
    result.frame_ms_mean = sum / static_cast<double>(frame_ms.size());
    // Nearest-rank 99th percentile.
    size_t rank = (frame_ms.size() * 99 + 99) / 100 - 1;
    std::nth_element(frame_ms.begin(), frame_ms.begin() + static_cast<ptrdiff_t>(rank), frame_ms.end());
    result.frame_ms_p99 = frame_ms[rank];
  }
  return result;
}

Result<RunResult> run_scene(const Scene& scene, ModelLibrary& library, const RunOptions& options,
                            const std::function<void(const FrameReport&)>& on_frame) {
  Result<SceneModels> models = load_scene_models(scene, library, options.lod.max_depth);
  if (!models) return models.error();
  return run_scene(scene, *models, options, on_frame);
}

void append_log_lines(const Scene& scene, const FrameReport& frame, std::string& out) {
  for (const Collision& c : frame.collisions) {
    append_int(out, frame.frame);
    out += ',';
    append_number(out, frame.time);
    out += ',';
    out += scene.objects[c.a].name;
    out += ',';
    out += scene.objects[c.b].name;
    out += ',';
    append_int(out, c.depth_a);
    out += ',';
    append_int(out, c.depth_b);
    out += ',';
    append_int(out, c.box_tests);
    for (const Eigen::Vector3d* p : {&c.position_a, &c.position_b}) {
      for (int k = 0; k < 3; ++k) {
        out += ',';
        append_number(out, (*p)[k]);
      }
    }
    out += '\n';
  }
}

}  // namespace octbake::scene
