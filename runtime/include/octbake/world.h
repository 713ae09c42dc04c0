// The built-in simulation: a thin layer over CollisionWorld (collision_world.h)
// that owns the motion (constant velocities, angular velocities, a camera
// path) and applies one of three collision responses. step() is
// deterministic: the same inputs give bit-identical states on every run and
// for every thread count.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "octbake/collide.h"
#include "octbake/collision_world.h"
#include "octbake/lod.h"
#include "octbake/motion.h"
#include "octbake/object_tree.h"
#include "octbake/pose.h"
#include "octbake/world_tree.h"
#include "octbake/export.h"

namespace octbake {

enum class Response { none, thesis, separate };
inline constexpr Response kResponses[] = {Response::none, Response::thesis, Response::separate};
// "none", "thesis", "separate": the names command lines and JSON use.
OCTBAKE_API const char* to_string(Response response);

struct ObjectDesc {
  std::string name;
  const ObjectTree* tree = nullptr;  // must outlive the World
  Pose pose;
  Eigen::Vector3d velocity{0, 0, 0};  // world units per second
  // rad/s about the world axes through the object's position. The
  // orientation at frame f is spun(pose.rotation, w, f * timestep) (motion.h),
  // computed from frame 0 every frame (no drift); responses never change it.
  // An object is static when both velocity and angular_velocity are zero.
  Eigen::Vector3d angular_velocity{0, 0, 0};
};

struct WorldSettings {
  Aabb bounds{{-100, -100, -100}, {100, 100, 100}};
  int world_depth = 4;
  double timestep = 1.0 / 30.0;
  Response response = Response::separate;
  LodSettings lod;
  Camera camera;
  bool areas_every_frame = false;  // else only when an object changes leaf set (or the camera moves)
  // Frames strictly ascending; empty = fixed camera. Interpolated by
  // camera_on_path (motion.h).
  std::vector<CameraKey> camera_path;
  int threads = 1;                     // CollisionSettings::threads; also the motion and the area passes of step()
  Executor* executor = nullptr;        // the app's job system, if any (not owned)
};

struct Collision {
  uint32_t a = 0, b = 0;  // object indices, a < b
  int depth_a = 0, depth_b = 0;
  uint64_t box_tests = 0;
  Eigen::Vector3d position_a{0, 0, 0}, position_b{0, 0, 0};  // at the tested frame
};

struct FrameStats {
  uint64_t pair_tests = 0;  // candidate pairs tested with ObjectTrees
  uint64_t pairs_reused = 0;  // of those, answered by last frame's result (DetectStats::pairs_reused)
  uint64_t pairs_kept_apart = 0;  // of those, misses kept by their separation (DetectStats::pairs_kept_apart)
  uint64_t box_tests = 0;
  uint64_t collisions = 0;
  uint64_t area_refreshes = 0;  // objects whose pixel area was recomputed
};

// Frame loop (docs/interface.md sections 4 and 5). Per step, for frame f:
//  0. Camera: with a camera path, the camera of frame f (a moved camera
//     makes every area stale).
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
//  4. Advance: orientation q(f+1) = R(w, (f+1) * timestep) * q(0);
//     position = p0 + v * ((f + 1 - f0) * timestep) from the last
//     motion change (p0 at frame f0), so positions do not drift with summed
//     timesteps. A component that would take the position (the mesh origin)
//     out of the world box while moving outward is reversed and the position
//     mirrored back inside about that face.
class OCTBAKE_API World {
 public:
  // Every object's tree must be non-null and outlive the World; poses valid
  // (asserted), camera_path frames strictly ascending (asserted).
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
  // Depth and pixel area as of the last step's LOD pass.
  int depth(size_t i) const { return world_.cached_depth(handles_[i]); }
  double area(size_t i) const { return world_.cached_area(handles_[i]); }
  const WorldSettings& settings() const { return settings_; }
  const WorldTree& world_tree() const { return world_.world_tree(); }
  const CollisionWorld& collision_world() const { return world_; }
  // The camera of frame f (settings().camera, moved along camera_path).
  Camera camera_at(int64_t f) const;

 private:
  WorldSettings settings_;
  std::vector<ObjectDesc> objects_;
  CollisionWorld world_;
  std::vector<ObjectHandle> handles_;  // handles_[i].slot == i
  int64_t frame_ = 0;

  // Per object, by index.
  std::vector<Eigen::Vector3d> origin_;  // position at frame start_ of the current motion
  std::vector<int64_t> start_;
  std::vector<Eigen::Quaterniond> rotation0_;  // orientation at frame 0
  std::vector<uint32_t> moving_;  // indices with non-zero velocity or angular velocity, ascending
  std::vector<ObjectHandle> moving_handles_;  // their handles
  std::vector<Pose> next_poses_;              // scratch: their poses for the next frame
  std::vector<Contact> contacts_;  // scratch

  void move_to(uint32_t i, const Eigen::Vector3d& p);  // position (and the collision world's pose)
  void restart_motion(uint32_t i, int64_t frame);       // the motion changed: p0, f0 = now
  void respond(const Collision& c);
  void advance(uint32_t i);  // objects_[i]'s pose (and velocity) one timestep on; thread-safe per i
};

}  // namespace octbake
