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
};

class World {
 public:
  World(WorldSettings settings, std::vector<ObjectDesc> objects);

  // Tests frame frame() at the current positions, appends its collisions
  // (sorted by (a, b)), applies the response, then advances every moving
  // object by one timestep (reversing a velocity component that would leave
  // the world box).
  FrameStats step(std::vector<Collision>& collisions);

  int64_t frame() const { return frame_; }
  size_t size() const { return objects_.size(); }
  const ObjectDesc& object(size_t i) const { return objects_[i]; }
  int depth(size_t i) const { return depths_[i]; }
  double area(size_t i) const { return areas_[i]; }
  const WorldSettings& settings() const { return settings_; }

 private:
  WorldSettings settings_;
  std::vector<ObjectDesc> objects_;
  std::vector<double> areas_;
  std::vector<int> depths_;
  WorldTree tree_;
  int64_t frame_ = 0;
  // Further state as the implementation needs (world.cpp owns it).
  void refresh_lod(bool all);
};

}  // namespace octbake
