#include "gen.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <random>

#include "octbake/world_tree.h"

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

// Uniform on the sphere, by rejection from the cube (3 draws per try).
Eigen::Vector3d random_direction(std::mt19937& rng) {
  Eigen::Vector3d dir;
  do {
    for (int k = 0; k < 3; ++k) dir[k] = uniform(rng, -1, 1);
  } while (dir.squaredNorm() > 1 || dir.squaredNorm() < 1e-4);
  return dir.normalized();
}

// Uniform over all orientations (Shoemake's subgroup algorithm).
Eigen::Quaterniond random_rotation(std::mt19937& rng) {
  const double u1 = uniform(rng), u2 = uniform(rng), u3 = uniform(rng);
  const double a = std::sqrt(1 - u1), b = std::sqrt(u1), tau = 2 * std::numbers::pi;
  return Eigen::Quaterniond(b * std::cos(tau * u3), a * std::sin(tau * u2), a * std::cos(tau * u2),
                            b * std::sin(tau * u3))
      .normalized();
}

// The box an object spinning about its origin stays in: the sphere through
// its farthest bounds corner.
Aabb spin_box(const Aabb& local, double scale) {
  double r = 0;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d p{(c & 1) ? local.max.x() : local.min.x(), (c & 2) ? local.max.y() : local.min.y(),
                            (c & 4) ? local.max.z() : local.min.z()};
    r = std::max(r, p.norm() * scale);
  }
  return {Eigen::Vector3d::Constant(-r), Eigen::Vector3d::Constant(r)};
}

bool share_ok(double share) { return share >= 0 && share <= 1; }

// A loop around the world centre at 0.3 of its size, rising and falling by
// 0.1, each key looking 0.6 rad ahead along the loop. The keys go once around;
// but 3 keys would be half a turn apart, and halfway between them the camera
// would sit at the centre looking straight up (a scene parse_scene rejects),
// so 3 keys are a third of a turn apart and the path stays open.
std::vector<CameraKey> flythrough(int keys, int64_t frames, double world_size) {
  auto at = [world_size](double angle) {
    return Eigen::Vector3d{0.3 * world_size * std::cos(angle), 0.1 * world_size * std::sin(2 * angle),
                           0.3 * world_size * std::sin(angle)};
  };
  std::vector<CameraKey> path;
  for (int k = 0; k < keys; ++k) {
    const double angle = 2 * std::numbers::pi * k / (keys == 3 ? 3 : keys - 1);
    CameraKey key;
    key.frame = frames / (keys - 1) * k + frames % (keys - 1) * k / (keys - 1);  // floor(frames k / (keys-1)), no overflow
    key.position = at(angle);
    key.look_at = at(angle + 0.6);
    path.push_back(key);
  }
  return path;
}

}  // namespace

Result<std::monostate> check_gen_options(const GenOptions& options) {
  if (options.models.empty()) return Error{ErrorCode::invalid_argument, "--models: need at least one model"};
  if (options.static_count < 0 || options.moving_count < 0)
    return Error{ErrorCode::invalid_argument, "object counts must be >= 0"};
  if (!(options.world_size > 0) || !std::isfinite(options.world_size))
    return Error{ErrorCode::invalid_argument, "--world: must be a positive size"};
  if (!(options.speed >= 0) || !std::isfinite(options.speed))
    return Error{ErrorCode::invalid_argument, "--speed: must be >= 0"};
  if (!(options.scale_min > 0) || !(options.scale_max >= options.scale_min) || !std::isfinite(options.scale_max))
    return Error{ErrorCode::invalid_argument, "--scale-range: need 0 < min <= max, both finite"};
  if (!share_ok(options.rotated_share)) return Error{ErrorCode::invalid_argument, "--rotated-share: must be in [0, 1]"};
  if (!share_ok(options.spin_share)) return Error{ErrorCode::invalid_argument, "--spin-share: must be in [0, 1]"};
  if (!share_ok(options.resting_share))
    return Error{ErrorCode::invalid_argument, "--resting-share: must be in [0, 1]"};
  if (!(options.spin_rate >= 0) || !std::isfinite(options.spin_rate))
    return Error{ErrorCode::invalid_argument, "--spin-rate: must be >= 0"};
  if (options.camera_keys == 1 || options.camera_keys < 0)
    return Error{ErrorCode::invalid_argument, "--camera-path: need at least 2 keys (or 0: a fixed camera)"};
  if (options.camera_keys >= 2 && options.frames < options.camera_keys - 1)
    return Error{ErrorCode::invalid_argument, "--camera-path: need at least one frame per key (--frames)"};
  return std::monostate{};
}

Result<Scene> generate_scene(const GenOptions& options, ModelLibrary& library) {
  if (auto st = check_gen_options(options); !st) return st.error();

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
  if (options.camera_keys >= 2) {
    scene.camera_path = flythrough(options.camera_keys, options.frames, options.world_size);
    scene.camera.position = scene.camera_path.front().position;
    scene.camera.look_at = scene.camera_path.front().look_at;
  }

  std::mt19937 rng(options.seed);
  std::map<std::string, int> per_model;
  const int total = options.static_count + options.moving_count;
  // The boxes placed so far, indexed by cells (about one per object): an
  // attempt is tested against those sharing a cell with it only, the same
  // answer as against all of them (boxes that touch share a cell) in linear
  // time instead of quadratic (100k objects over 400x sizes: 46 -> 1.3 s).
  std::vector<Aabb> placed;
  WorldTree index(scene.world, std::clamp(int(std::ceil(std::log2(std::max(total, 1)) / 3)), 0, 8));
  std::vector<uint32_t> near;
  for (int n = 0; n < total; ++n) {
    size_t m = rng() % options.models.size();
    SceneObject o;
    o.model = options.models[m];
    o.name = o.model + "_" + std::to_string(per_model[o.model]++);
    // Each option draws only when it is used (see GenOptions).
    if (options.scale_min < options.scale_max)
      o.pose.scale = std::exp(uniform(rng, std::log(options.scale_min), std::log(options.scale_max)));
    else
      o.pose.scale = options.scale_min;
    const bool rotated = options.rotated_share > 0 && uniform(rng) < options.rotated_share;
    const bool spinning = options.spin_share > 0 && uniform(rng) < options.spin_share;
    // Rests against an earlier static (statics come first: any placed box).
    const bool resting = n > 0 && n < options.static_count && options.resting_share > 0 &&
                         uniform(rng) < options.resting_share;
    size_t against = 0;
    bool ok = false;
    for (int attempt = 0; attempt < kAttemptsPerObject && !ok; ++attempt) {
      if (rotated) {
        o.pose.rotation = random_rotation(rng);
      } else {
        double yaw = uniform(rng, 0, 2 * std::numbers::pi);
        o.pose.rotation = Eigen::Quaterniond(std::cos(yaw / 2), 0, std::sin(yaw / 2), 0);
      }
      o.pose.position.setZero();
      Aabb at_origin = spinning ? spin_box(bounds[m], o.pose.scale) : world_bounds(place(bounds[m], o.pose));
      // Positions that keep the whole box inside the world.
      Eigen::Vector3d lo = scene.world.min - at_origin.min, hi = scene.world.max - at_origin.max;
      if ((lo.array() > hi.array()).any()) break;  // larger than the world
      if (resting) {
        // On one side of a placed box along axis k, sunk into it by a fifth
        // of the smaller extent; centred anywhere over it on the other axes,
        // moved into the world on those if need be (still over it, or
        // retried).
        against = rng() % placed.size();
        const Aabb& other = placed[against];
        const int k = int(rng() % 3);
        const bool above = rng() % 2 != 0;
        const Eigen::Vector3d size = at_origin.max - at_origin.min, other_size = other.max - other.min;
        const double sink = 0.2 * std::min(size[k], other_size[k]);
        for (int i = 0; i < 3; ++i)
          o.pose.position[i] = uniform(rng, other.min[i], other.max[i]) - 0.5 * (at_origin.min[i] + at_origin.max[i]);
        o.pose.position[k] = above ? other.max[k] - sink - at_origin.min[k] : other.min[k] + sink - at_origin.max[k];
        if (o.pose.position[k] < lo[k] || o.pose.position[k] > hi[k]) continue;  // no room on that side
        // A hair inside the walls: the box placed at a wall, recomputed from
        // the pose, may round a few ulps outside.
        const double margin = 1e-9 * options.world_size;
        o.pose.position = o.pose.position.cwiseMax((lo.array() + margin).matrix()).cwiseMin((hi.array() - margin).matrix());
        if (!overlap({at_origin.min + o.pose.position, at_origin.max + o.pose.position}, other)) continue;
      } else {
        for (int k = 0; k < 3; ++k) o.pose.position[k] = uniform(rng, lo[k], hi[k]);
      }
      Aabb box{at_origin.min + o.pose.position, at_origin.max + o.pose.position};
      index.query_box(box, near);
      ok = std::none_of(near.begin(), near.end(),
                        [&](uint32_t i) { return !(resting && i == against) && overlap(box, placed[i]); });
      if (ok) {
        index.update(uint32_t(placed.size()), box);
        placed.push_back(box);
      }
    }
    if (!ok)
      return Error{ErrorCode::invalid_argument, "cannot place " + o.name + " without an overlap after " +
                                                    std::to_string(kAttemptsPerObject) +
                                                    " tries; use a larger --world or fewer objects"};
    // Direction first, then magnitude (separate statements: operands of * are unsequenced).
    if (n >= options.static_count && options.speed > 0) {
      const Eigen::Vector3d dir = random_direction(rng);
      o.velocity = dir * (options.speed * uniform(rng, 0.5, 1));
    }
    if (spinning && options.spin_rate > 0) {
      const Eigen::Vector3d axis = random_direction(rng);
      o.angular_velocity = axis * (options.spin_rate * uniform(rng, 0.5, 1));
    }
    scene.objects.push_back(std::move(o));
  }
  return scene;
}

}  // namespace octbake::scene
