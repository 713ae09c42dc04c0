// `octscene gen`: random scenes for benchmarks and the thesis's experiments.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "octbake/baked_file.h"
#include "octbake/result.h"
#include "scene.h"

namespace octbake::scene {

struct GenOptions {
  int static_count = 0;
  int moving_count = 0;
  uint32_t seed = 1;
  std::vector<std::string> models;  // picked uniformly per object
  double world_size = 200;          // edge of the cubic world box, centred on the origin
  double speed = 5;                 // moving objects get speeds in [speed/2, speed)
  int world_depth = 4;
  double timestep = 1.0 / 30.0;
  int64_t frames = 7200;
};

// Objects are placed uniformly with random yaw, each wholly inside the world
// box and with a world AABB (of its rotated bounds) disjoint from every earlier
// one, so no pair overlaps at frame 0. Statics come first, named
// "<model>_<k>". The same options and trees give the same scene on every
// machine (std::mt19937, floats made from its raw output).
// `library` supplies the models' bounds (headers only). Scene::baked is left
// empty: the caller decides how the file refers to the trees.
Result<Scene> generate_scene(const GenOptions& options, ModelLibrary& library);

}  // namespace octbake::scene
