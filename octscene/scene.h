// Scene files (docs/interface.md section 4): strict parsing and validation.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "octbake/lod.h"
#include "octbake/motion.h"
#include "octbake/pose.h"
#include "octbake/result.h"

namespace octbake::scene {

// Largest frame count of a scene, `--frames` and `--frame`: run keeps one
// time per frame.
constexpr int64_t kMaxFrames = 100'000'000;

struct SceneObject {
  std::string name;
  std::string model;
  Pose pose;
  Eigen::Vector3d velocity{0, 0, 0};
  // Radians per second about world axes through the position; the orientation
  // at frame f is spun(pose.rotation, angular_velocity, f * timestep).
  Eigen::Vector3d angular_velocity{0, 0, 0};
};

struct Scene {
  std::string baked;     // resolved against the scene file's folder
  Camera camera;
  // Frames strictly ascending, each >= 0; empty: `camera` at every frame. The
  // camera at frame f is camera_on_path(camera, camera_path, f).
  std::vector<CameraKey> camera_path;
  Aabb world;
  int world_depth = 4;
  double timestep = 1.0 / 30.0;
  int64_t frames = 0;
  std::vector<SceneObject> objects;
};

// Error messages name the JSON path and the reason, e.g.
// "objects[12].rotation: not a unit quaternion" or "camera_path[2].frame:
// frames must be strictly ascending". Model names are not checked
// here (see run.h): parsing needs no baked files.
Result<Scene> parse_scene(const std::string& json_text, const std::string& scene_dir);
Result<Scene> load_scene(const std::string& path);

// The scene as JSON that parse_scene() accepts, one object per line; numbers
// are printed so they read back to the same doubles. `baked` is written as
// given (Scene::baked holds the resolved path). "angular_velocity" is written
// only when non-zero and "camera_path" only when non-empty, so scenes without
// motion read and write exactly as before these keys existed.
std::string write_scene(const Scene& scene, const std::string& baked);

}  // namespace octbake::scene
