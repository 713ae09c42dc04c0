// Scene files (docs/interface.md section 4): strict parsing and validation.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "octbake/lod.h"
#include "octbake/pose.h"
#include "octbake/result.h"

namespace octbake::scene {

struct SceneObject {
  std::string name;
  std::string model;
  Pose pose;
  Eigen::Vector3d velocity{0, 0, 0};
};

struct Scene {
  std::string baked;     // resolved against the scene file's folder
  Camera camera;
  Aabb world;
  int world_depth = 4;
  double timestep = 1.0 / 30.0;
  int64_t frames = 0;
  std::vector<SceneObject> objects;
};

// Error messages name the JSON path and the reason, e.g.
// "objects[12].rotation: not a unit quaternion". Model names are not checked
// here (see run.h): parsing needs no baked files.
Result<Scene> parse_scene(const std::string& json_text, const std::string& scene_dir);
Result<Scene> load_scene(const std::string& path);

// The scene as JSON that parse_scene() accepts, one object per line; numbers
// are printed so they read back to the same doubles. `baked` is written as
// given (Scene::baked holds the resolved path).
std::string write_scene(const Scene& scene, const std::string& baked);

}  // namespace octbake::scene
