// The World of commit 68d2b0b (before CollisionWorld), kept verbatim as
// LegacyWorld so bench_world compares the new detect() against "our own
// fixed-camera step today" in one run. Benchmark-only code.
#pragma once
#include <algorithm>
#include <cassert>
#include <cmath>
#include "octbake/world.h"
namespace octbake::legacy {
class World {
 public:
  using Collision = octbake::Collision;
 public:
  // Every object's tree must be non-null and outlive the World.
  World(WorldSettings settings, std::vector<ObjectDesc> objects);

  // Tests frame frame() at the current positions, appends its collisions
  // (sorted by (a, b)), applies the response, then advances every moving
  // object by one timestep (reversing a velocity component that would leave
  // the world box).
  FrameStats step(std::vector<Collision>& collisions);

  int64_t frame() const { return frame_; }
  size_t size() const { return objects_.size(); }
  // Current pose and velocity (positions as of frame()).
  const ObjectDesc& object(size_t i) const { return objects_[i]; }
  int depth(size_t i) const { return depths_[i]; }
  double area(size_t i) const { return areas_[i]; }
  const WorldSettings& settings() const { return settings_; }
  const WorldTree& world_tree() const { return tree_; }

 private:
  WorldSettings settings_;
  std::vector<ObjectDesc> objects_;
  std::vector<double> areas_;
  std::vector<int> depths_;
  WorldTree tree_;
  int64_t frame_ = 0;

  // Per object, by index. Hot (per frame) first.
  std::vector<Aabb> box_;              // world AABB at the current position, padded
  std::vector<Aabb> offset_box_;       // world AABB relative to the position (fixed: no spin)
  std::vector<Eigen::Vector3d> origin_;  // position at frame start_ of the current motion
  std::vector<int64_t> start_;
  std::vector<uint8_t> stale_area_;
  std::vector<int> max_depths_;
  std::vector<uint32_t> moving_;       // indices with non-zero velocity, ascending
  std::vector<std::pair<uint32_t, uint32_t>> pairs_;  // scratch

  uint64_t refresh_lod(bool all);
  void move_to(uint32_t i, const Eigen::Vector3d& p);  // position and box
  void restart_motion(uint32_t i, int64_t frame);       // the motion changed: p0, f0 = now
  void respond(const Collision& c);
  void advance(uint32_t i);
};
namespace {

// World AABBs are padded by this fraction of their coordinates' magnitude so
// that rounding in the pre-filter never rejects a pair collide() would accept
// (collide() pads its boxes too).
constexpr double kRelativePad = 1e-9;

}  // namespace

World::World(WorldSettings settings, std::vector<ObjectDesc> objects)
    : settings_(std::move(settings)), objects_(std::move(objects)), tree_(settings_.bounds, settings_.world_depth) {
  const size_t n = objects_.size();
  assert(n < (size_t{1} << 32));
  areas_.assign(n, 0.0);
  depths_.assign(n, 0);
  box_.resize(n);
  offset_box_.resize(n);
  origin_.resize(n);
  start_.assign(n, 0);
  stale_area_.assign(n, 1);
  max_depths_.resize(n);
  for (uint32_t i = 0; i < n; ++i) {
    const ObjectDesc& o = objects_[i];
    assert(o.tree != nullptr);
    assert(o.pose.scale > 0 && !o.pose.position.hasNaN() && !o.velocity.hasNaN());
    Pose at_origin = o.pose;
    at_origin.position.setZero();
    offset_box_[i] = world_bounds(place(o.tree->bounds(), at_origin));
    origin_[i] = o.pose.position;
    max_depths_[i] = o.tree->loaded_depth();
    if (!o.velocity.isZero(0)) moving_.push_back(i);
    move_to(i, o.pose.position);
    (void)tree_.update(i, box_[i]);
  }
}

void World::restart_motion(uint32_t i, int64_t frame) {
  origin_[i] = objects_[i].pose.position;
  start_[i] = frame;
}

void World::move_to(uint32_t i, const Eigen::Vector3d& p) {
  objects_[i].pose.position = p;
  const Aabb& off = offset_box_[i];
  const double pad =
      kRelativePad * (p.cwiseAbs().maxCoeff() + std::max(off.min.cwiseAbs().maxCoeff(), off.max.cwiseAbs().maxCoeff()));
  box_[i].min = (p + off.min).array() - pad;
  box_[i].max = (p + off.max).array() + pad;
}

uint64_t World::refresh_lod(bool all) {
  std::vector<uint32_t> ids;
  for (uint32_t i = 0; i < objects_.size(); ++i) {
    if (!all && !stale_area_[i]) continue;
    const ObjectDesc& o = objects_[i];
    areas_[i] = pixel_area(settings_.camera, place(o.tree->bounds(), o.pose));
    stale_area_[i] = 0;
    ids.push_back(i);
  }
  const uint64_t refreshed = ids.size();
  if (ids.empty()) return 0;
  std::vector<int> depths;
  if (all || settings_.lod.policy == LodPolicy::thesis) {
    // The thesis formula depends on every area (A_min, A_max).
    depths = choose_depths(settings_.lod, areas_, max_depths_);
    ids.resize(objects_.size());
    for (uint32_t i = 0; i < ids.size(); ++i) ids[i] = i;
  } else {
    std::vector<double> areas;
    std::vector<int> max_depths;
    for (uint32_t i : ids) {
      areas.push_back(areas_[i]);
      max_depths.push_back(max_depths_[i]);
    }
    depths = choose_depths(settings_.lod, areas, max_depths);
  }
  for (size_t k = 0; k < ids.size(); ++k) depths_[ids[k]] = std::clamp(depths[k], 0, max_depths_[ids[k]]);
  return refreshed;
}

FrameStats World::step(std::vector<Collision>& collisions) {
  FrameStats stats;
  stats.area_refreshes = refresh_lod(frame_ == 0 || settings_.areas_every_frame);

  tree_.candidate_pairs(pairs_);
  const size_t first = collisions.size();
  for (const auto& [a, b] : pairs_) {
    if (!overlaps(box_[a], box_[b])) continue;
    const ObjectDesc& oa = objects_[a];
    const ObjectDesc& ob = objects_[b];
    const PairTest t = collide({oa.tree, oa.pose, depths_[a]}, {ob.tree, ob.pose, depths_[b]});
    ++stats.pair_tests;
    stats.box_tests += t.box_tests;
    if (!t.hit) continue;
    collisions.push_back({a, b, depths_[a], depths_[b], t.box_tests, oa.pose.position, ob.pose.position});
  }
  stats.collisions = collisions.size() - first;

  if (settings_.response != Response::none)
    for (size_t k = first; k < collisions.size(); ++k) respond(collisions[k]);
  for (uint32_t i : moving_) advance(i);
  ++frame_;
  return stats;
}

void World::respond(const Collision& c) {
  const bool move_a = !objects_[c.a].velocity.isZero(0), move_b = !objects_[c.b].velocity.isZero(0);
  if (!move_a && !move_b) return;
  Eigen::Vector3d& va = objects_[c.a].velocity;
  Eigen::Vector3d& vb = objects_[c.b].velocity;

  if (settings_.response == Response::thesis) {
    const double l = (va.norm() + vb.norm()) * 1.5 * settings_.timestep;
    for (uint32_t i : {c.a, c.b}) {
      Eigen::Vector3d& v = objects_[i].velocity;
      if (v.isZero(0)) continue;
      v = -v;
      move_to(i, objects_[i].pose.position + v.normalized() * l);
      restart_motion(i, frame_);
    }
    return;
  }

  // separate: the boxes as they are now (an earlier response this frame may
  // already have moved them apart).
  const Aabb& ba = box_[c.a];
  const Aabb& bb = box_[c.b];
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
  const Eigen::Vector3d current = o.pose.position;
  Eigen::Vector3d p = origin_[i] + o.velocity * (double(frame_ + 1 - start_[i]) * settings_.timestep);
  const Aabb& w = settings_.bounds;
  bool bounced = false;
  for (int k = 0; k < 3; ++k) {
    const bool below = p[k] < w.min[k] && o.velocity[k] < 0;
    const bool above = p[k] > w.max[k] && o.velocity[k] > 0;
    if (!below && !above) continue;
    o.velocity[k] = -o.velocity[k];
    bounced = true;
    // Mirror about the face it would cross; an object already outside on this
    // axis just stops going further out.
    if (current[k] < w.min[k] || current[k] > w.max[k])
      p[k] = current[k];
    else
      p[k] = std::clamp(below ? 2 * w.min[k] - p[k] : 2 * w.max[k] - p[k], w.min[k], w.max[k]);
  }
  move_to(i, p);
  if (bounced) restart_motion(i, frame_ + 1);
  if (tree_.update(i, box_[i])) stale_area_[i] = 1;
}

}  // namespace octbake::legacy
