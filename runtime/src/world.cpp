#include "octbake/world.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace octbake {

const char* to_string(Response response) {
  switch (response) {
    case Response::none: return "none";
    case Response::thesis: return "thesis";
    case Response::separate: return "separate";
  }
  return "?";
}

namespace {

CollisionSettings collision_settings(const WorldSettings& s, const Camera& camera) {
  CollisionSettings c;
  c.bounds = s.bounds;
  c.world_depth = s.world_depth;
  c.lod = s.lod;
  c.camera = camera;
  c.area_refresh = s.areas_every_frame ? AreaRefresh::every_frame : AreaRefresh::on_cell_change;
  c.threads = s.threads;
  c.executor = s.executor;
  return c;
}

bool is_moving(const ObjectDesc& o) { return !o.velocity.isZero(0) || !o.angular_velocity.isZero(0); }

constexpr size_t kAdvanceGrain = 512;  // moving objects per chunk (~50 ns each)

}  // namespace

Camera World::camera_at(int64_t f) const { return camera_on_path(settings_.camera, settings_.camera_path, f); }

World::World(WorldSettings settings, std::vector<ObjectDesc> objects)
    : settings_(std::move(settings)), objects_(std::move(objects)), world_(collision_settings(settings_, camera_at(0))) {
  for (size_t k = 1; k < settings_.camera_path.size(); ++k)
    assert(settings_.camera_path[k - 1].frame < settings_.camera_path[k].frame);
  const size_t n = objects_.size();
  assert(n < (size_t{1} << 31));
  origin_.resize(n);
  start_.assign(n, 0);
  rotation0_.resize(n);
  handles_.reserve(n);
  for (uint32_t i = 0; i < n; ++i) {
    const ObjectDesc& o = objects_[i];
    assert(o.tree != nullptr && !o.velocity.hasNaN() && o.angular_velocity.allFinite());
    Result<ObjectHandle> h = world_.create(TreeSource::fixed(o.tree), o.pose);
    assert(h.ok() && h->slot == i);
    handles_.push_back(h.ok() ? *h : ObjectHandle{});
    origin_[i] = o.pose.position;
    rotation0_[i] = o.pose.rotation;
    if (is_moving(o)) moving_.push_back(i), moving_handles_.push_back(handles_.back());
  }
  next_poses_.resize(moving_.size());
  world_.commit_poses();
}

void World::restart_motion(uint32_t i, int64_t frame) {
  origin_[i] = objects_[i].pose.position;
  start_[i] = frame;
}

void World::move_to(uint32_t i, const Eigen::Vector3d& p) {
  objects_[i].pose.position = p;
  const Status st = world_.set_pose(handles_[i], objects_[i].pose);
  assert(st.ok());
  (void)st;
}

FrameStats World::step(std::vector<Collision>& collisions) {
  world_.set_camera(camera_at(frame_));
  const DetectStats d = world_.detect(contacts_);
  FrameStats stats;
  stats.pair_tests = d.pair_tests;
  stats.pairs_reused = d.pairs_reused;
  stats.pairs_kept_apart = d.pairs_kept_apart;
  stats.box_tests = d.box_tests;
  stats.collisions = d.contacts;
  stats.area_refreshes = d.area_computations;

  const size_t first = collisions.size();
  for (const Contact& c : contacts_)
    collisions.push_back({c.a.slot, c.b.slot, c.depth_a, c.depth_b, c.box_tests, objects_[c.a.slot].pose.position,
                          objects_[c.b.slot].pose.position});

  if (settings_.response != Response::none)
    for (size_t k = first; k < collisions.size(); ++k) respond(collisions[k]);
  // Every moving object's next pose. On threads, each computes its own
  // objects' poses, then one set_poses (the same as one set_pose each); on one
  // thread, or a batch too small to split, one set_pose per object is cheaper
  // (set_poses passes over the batch twice).
  if (world_.has_threads() && moving_.size() > kAdvanceGrain) {
    const auto advance_range = [this](size_t b, size_t e) {
      for (size_t k = b; k < e; ++k) {
        advance(moving_[k]);
        next_poses_[k] = objects_[moving_[k]].pose;
      }
    };
    world_.run_parallel(moving_.size(), kAdvanceGrain, range_task(advance_range));
    const Status st = world_.set_poses(moving_handles_, next_poses_);
    assert(st.ok());
    (void)st;
  } else {
    for (uint32_t i : moving_) {
      advance(i);
      move_to(i, objects_[i].pose.position);
    }
  }
  world_.commit_poses();  // world_tree() shows the next frame's cells, as before
  ++frame_;
  return stats;
}

void World::respond(const Collision& c) {
  const bool move_a = is_moving(objects_[c.a]), move_b = is_moving(objects_[c.b]);
  if (!move_a && !move_b) return;
  Eigen::Vector3d& va = objects_[c.a].velocity;
  Eigen::Vector3d& vb = objects_[c.b].velocity;

  if (settings_.response == Response::thesis) {
    const double l = (va.norm() + vb.norm()) * 1.5 * settings_.timestep;
    for (uint32_t i : {c.a, c.b}) {
      Eigen::Vector3d& v = objects_[i].velocity;
      if (v.isZero(0)) continue;  // static, or only spinning: nothing to reverse
      v = -v;
      move_to(i, objects_[i].pose.position + v.normalized() * l);
      restart_motion(i, frame_);
    }
    return;
  }

  // separate: the boxes as they are now (an earlier response this frame may
  // already have moved them apart).
  const Aabb& ba = world_.bounds(handles_[c.a]);
  const Aabb& bb = world_.bounds(handles_[c.b]);
  const Eigen::Vector3d depth = ba.max.cwiseMin(bb.max) - ba.min.cwiseMax(bb.min);
  if ((depth.array() < 0).any()) return;
  int k = 0;
  for (int j = 1; j < 3; ++j)
    if (depth[j] < depth[k]) k = j;
  // s: the direction a is pushed along axis k (away from b).
  const double s = (ba.min[k] + ba.max[k] <= bb.min[k] + bb.max[k]) ? -1.0 : 1.0;
  const double share = (move_a && move_b) ? 0.5 * depth[k] : depth[k];
  const bool approaching = (va[k] - vb[k]) * -s > 0;
  if (move_a) {
    Eigen::Vector3d p = objects_[c.a].pose.position;
    p[k] += s * share;
    if (approaching && va[k] * -s > 0) va[k] = -va[k];
    move_to(c.a, p);
    restart_motion(c.a, frame_);
  }
  if (move_b) {
    Eigen::Vector3d p = objects_[c.b].pose.position;
    p[k] -= s * share;
    if (approaching && vb[k] * s > 0) vb[k] = -vb[k];
    move_to(c.b, p);
    restart_motion(c.b, frame_);
  }
}

void World::advance(uint32_t i) {
  ObjectDesc& o = objects_[i];
  const Eigen::Vector3d& w = o.angular_velocity;
  // From frame 0 every frame: no drift, and responses never touch it.
  if (!w.isZero(0)) o.pose.rotation = spun(rotation0_[i], w, double(frame_ + 1) * settings_.timestep);
  if (o.velocity.isZero(0)) return;
  const Eigen::Vector3d current = o.pose.position;
  Eigen::Vector3d p = origin_[i] + o.velocity * (double(frame_ + 1 - start_[i]) * settings_.timestep);
  const Aabb& box = settings_.bounds;
  bool bounced = false;
  for (int k = 0; k < 3; ++k) {
    const bool below = p[k] < box.min[k] && o.velocity[k] < 0;
    const bool above = p[k] > box.max[k] && o.velocity[k] > 0;
    if (!below && !above) continue;
    o.velocity[k] = -o.velocity[k];
    bounced = true;
    // Mirror about the face it would cross; an object already outside on this
    // axis just stops going further out.
    if (current[k] < box.min[k] || current[k] > box.max[k])
      p[k] = current[k];
    else
      p[k] = std::clamp(below ? 2 * box.min[k] - p[k] : 2 * box.max[k] - p[k], box.min[k], box.max[k]);
  }
  o.pose.position = p;
  if (bounced) restart_motion(i, frame_ + 1);
}

}  // namespace octbake
