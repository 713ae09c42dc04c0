// A scene in motion: objects on the WorldTree, LOD depths from pixel areas,
// conservative pair tests and a collision response. step() is deterministic:
// the same inputs give bit-identical states on every run.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "octbake/collide.h"
#include "octbake/lod.h"
#include "octbake/object_tree.h"
#include "octbake/pose.h"
#include "octbake/world_tree.h"
#include "octbake/export.h"

namespace octbake {

enum class Response { none, thesis, separate };

struct ObjectDesc {
  std::string name;
  const ObjectTree* tree = nullptr;  // must outlive the World
  Pose pose;
  Eigen::Vector3d velocity{0, 0, 0};  // world units per second; zero = static
};

struct WorldSettings {
  Aabb bounds{{-100, -100, -100}, {100, 100, 100}};
  int world_depth = 4;
  double timestep = 1.0 / 30.0;
  Response response = Response::separate;
  LodSettings lod;
  Camera camera;
  bool areas_every_frame = false;  // else only when an object changes leaf set
};

struct Collision {
  uint32_t a = 0, b = 0;  // object indices, a < b
  int depth_a = 0, depth_b = 0;
  uint64_t box_tests = 0;
  Eigen::Vector3d position_a{0, 0, 0}, position_b{0, 0, 0};  // at the tested frame
};

struct FrameStats {
  uint64_t pair_tests = 0;  // candidate pairs tested with ObjectTrees
  uint64_t box_tests = 0;
  uint64_t collisions = 0;
  uint64_t area_refreshes = 0;  // objects whose pixel area was recomputed
};

// Frame loop (docs/interface.md sections 4 and 5). Per step, for frame f:
//  1. LOD: recompute the pixel area of every object whose leaf set changed
//     since its last refresh (all on the first frame, or every frame with
//     areas_every_frame), then depths by choose_depths, each object's max depth
//     being its tree's loaded_depth().
//  2. Pairs: WorldTree candidates, rejected first by the objects' world AABBs
//     (a pre-filter, not counted as box tests: the descent's own root-root
//     test is), then collide() at each object's depth. Static-static pairs are
//     tested too.
//  3. Response, in (a, b) order. none: nothing. thesis: each moving object of
//     the pair has its velocity reversed and moves l = (|v_a| + |v_b|) * 1.5 *
//     timestep along its new direction. separate: the moving object(s) are
//     pushed apart along the least-penetration axis of the two world AABBs
//     (split evenly when both move), and when they approach on that axis each
//     one's velocity component toward the other is reversed. Static objects
//     (zero velocity) never move.
//  4. Advance: position = p0 + v * ((f + 1 - f0) * timestep) from the last
//     motion change (p0 at frame f0), so positions do not drift with summed
//     timesteps. A component that would take the position (the mesh origin)
//     out of the world box while moving outward is reversed and the position
//     mirrored back inside about that face.
class OCTBAKE_API World {
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

}  // namespace octbake
