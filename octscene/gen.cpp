#include "gen.h"

#include <cmath>
#include <map>
#include <numbers>
#include <random>

namespace octbake::scene {
namespace {

constexpr int kAttemptsPerObject = 20000;

// Uniform in [0, 1) from 53 raw bits, identical on every standard library.
double uniform(std::mt19937& rng) {
  uint64_t hi = rng() >> 5, lo = rng() >> 6;  // 27 + 26 bits
  return static_cast<double>((hi << 26) | lo) * 0x1p-53;
}

double uniform(std::mt19937& rng, double lo, double hi) { return lo + (hi - lo) * uniform(rng); }

bool overlap(const Aabb& a, const Aabb& b) {
  return (a.min.array() <= b.max.array()).all() && (b.min.array() <= a.max.array()).all();
}

}  // namespace

Result<Scene> generate_scene(const GenOptions& options, ModelLibrary& library) {
  if (options.models.empty()) return Error{ErrorCode::invalid_argument, "--models: need at least one model"};
  if (options.static_count < 0 || options.moving_count < 0)
    return Error{ErrorCode::invalid_argument, "object counts must be >= 0"};
  if (!(options.world_size > 0) || !std::isfinite(options.world_size))
    return Error{ErrorCode::invalid_argument, "--world: must be a positive size"};
  if (!(options.speed >= 0) || !std::isfinite(options.speed))
    return Error{ErrorCode::invalid_argument, "--speed: must be >= 0"};

  std::vector<Aabb> bounds;
  for (const std::string& m : options.models) {
    Result<TreeInfo> info = library.info(m);
    if (!info) return Error{info.error().code, "--models: " + m + ": " + info.error().message};
    bounds.push_back(info->bounds);
  }

  Scene scene;
  const double h = options.world_size / 2;
  scene.world = {{-h, -h, -h}, {h, h, h}};
  scene.world_depth = options.world_depth;
  scene.timestep = options.timestep;
  scene.frames = options.frames;
  // From outside one corner of the box's front face, so depth and pixel area vary.
  scene.camera.position = {0.15 * options.world_size, 0.35 * options.world_size, -1.1 * options.world_size};
  scene.camera.look_at = {0, 0, 0};
  scene.camera.far_plane = 10 * options.world_size;

  std::mt19937 rng(options.seed);
  std::map<std::string, int> per_model;
  std::vector<Aabb> placed;
  const int total = options.static_count + options.moving_count;
  for (int n = 0; n < total; ++n) {
    size_t m = rng() % options.models.size();
    SceneObject o;
    o.model = options.models[m];
    o.name = o.model + "_" + std::to_string(per_model[o.model]++);
    bool ok = false;
    for (int attempt = 0; attempt < kAttemptsPerObject && !ok; ++attempt) {
      double yaw = uniform(rng, 0, 2 * std::numbers::pi);
      o.pose.rotation = Eigen::Quaterniond(std::cos(yaw / 2), 0, std::sin(yaw / 2), 0);
      o.pose.position.setZero();
      Aabb at_origin = world_bounds(place(bounds[m], o.pose));
      // Positions that keep the whole box inside the world.
      Eigen::Vector3d lo = scene.world.min - at_origin.min, hi = scene.world.max - at_origin.max;
      if ((lo.array() > hi.array()).any()) break;  // larger than the world
      for (int k = 0; k < 3; ++k) o.pose.position[k] = uniform(rng, lo[k], hi[k]);
      Aabb box{at_origin.min + o.pose.position, at_origin.max + o.pose.position};
      ok = true;
      for (const Aabb& other : placed) ok = ok && !overlap(box, other);
      if (ok) placed.push_back(box);
    }
    if (!ok)
      return Error{ErrorCode::invalid_argument, "cannot place " + o.name + " without an overlap after " +
                                                    std::to_string(kAttemptsPerObject) +
                                                    " tries; use a larger --world or fewer objects"};
    if (n >= options.static_count && options.speed > 0) {
      Eigen::Vector3d dir;
      do {
        for (int k = 0; k < 3; ++k) dir[k] = uniform(rng, -1, 1);
      } while (dir.squaredNorm() > 1 || dir.squaredNorm() < 1e-4);  // uniform direction
      o.velocity = dir.normalized() * (options.speed * uniform(rng, 0.5, 1));
    }
    scene.objects.push_back(std::move(o));
  }
  return scene;
}

}  // namespace octbake::scene
