// `octscene gen`: random scenes for benchmarks and the thesis's experiments.
#pragma once
#include <cstdint>
#include <string>
#include <variant>
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
  // Motion and size extensions; each default draws no random numbers, so
  // scenes generated without them keep their bytes.
  double scale_min = 1, scale_max = 1;  // scales log-uniform in [min, max]
  double rotated_share = 0;  // share of objects with a uniform random 3D orientation (else a random yaw)
  double spin_share = 0;     // share of objects given an angular velocity
  double spin_rate = 1;      // spinning objects get rates in [rate/2, rate) rad/s about a random axis
  int camera_keys = 0;       // >= 2: a camera path of that many keys flying through the world box
  double resting_share = 0;  // share of statics (after the first) placed against an earlier static
};

// Objects are placed uniformly with random yaw (or a random orientation, a
// rotated_share of them), each wholly inside the world box and with a world
// AABB (of its rotated bounds; for a spinning object, of the sphere it spins
// in) disjoint from every earlier one, so no pair overlaps at frame 0; but a
// resting_share of the statics (drawn per static after the first) rest
// against an earlier static picked at random: their world AABBs overlap by
// a fifth of the smaller box's extent on one axis (their meshes may touch or
// not), and disjoint from every other box. Such pairs are candidates every
// frame that never change: static clutter, props on props.
// Whether an object is rotated or spins is drawn per object. Statics (zero
// velocity; they may spin) come first, named
// "<model>_<k>". The same options and trees give the same scene on every
// machine (std::mt19937, floats made from its raw output).
// The camera path, if asked for, is a closed loop at 0.3 of the world size
// around the centre, rising and falling, keys evenly spread over the frames,
// each looking a little ahead along the loop.
// `library` supplies the models' bounds (headers only). Scene::baked is left
// empty: the caller decides how the file refers to the trees.
Result<Scene> generate_scene(const GenOptions& options, ModelLibrary& library);

// generate_scene's checks of the options alone (no trees needed): a bad
// value or combination, named by its option.
Result<std::monostate> check_gen_options(const GenOptions& options);

}  // namespace octbake::scene
