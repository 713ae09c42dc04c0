// The exact mesh-mesh answer that `octscene trade` and the FCL benchmark score
// octbake against: FCL's OBBRSS BVH test on the source triangles.
//
// "Exact" means the two surfaces intersect (or touch, to FCL's rounding). A
// mesh wholly inside another without touching its surface is not a contact,
// which matches surface occupancy.
#pragma once
#include <fcl/geometry/bvh/BVH_model.h>

#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "octbake/baker.h"  // Mesh, load_mesh
#include "octbake/pose.h"
#include "octbake/result.h"

namespace octbake::scene {

using Bvh = fcl::BVHModel<fcl::OBBRSSd>;

// The mesh for model `model` in `dir`: the first of DIR/model.obj, .ply, .stl,
// .off, .gltf, .glb, .dae, .fbx that exists, or "" when none does.
std::string find_mesh(const std::string& dir, const std::string& model);

// A BVH over `mesh` with every vertex scaled by `scale` (FCL transforms are
// rigid, so a scaled instance needs its own BVH).
std::shared_ptr<Bvh> build_bvh(const Mesh& mesh, double scale);

// fcl::Transform3d for the rigid part of `pose` (the scale lives in the BVH).
fcl::Transform3d to_fcl(const Pose& pose);

// Do two placed BVHs intersect? (FCL collide, one contact, no contact data.)
bool bvh_collide(const Bvh& a, const Pose& pose_a, const Bvh& b, const Pose& pose_b);

// Meshes by model id, BVHs built once per distinct (model, scale).
class ExactMeshes {
 public:
  // Returns the new model's id (0, 1, ...).
  int add(Mesh mesh);
  const Mesh& mesh(int model) const { return meshes_[model]; }
  // The BVH of `model` at `scale`, built on first use.
  const Bvh& bvh(int model, double scale);
  bool collide(int model_a, const Pose& a, int model_b, const Pose& b);
  size_t bvh_count() const { return bvhs_.size(); }

 private:
  std::vector<Mesh> meshes_;
  std::map<std::pair<int, double>, std::shared_ptr<Bvh>> bvhs_;
};

// FCL squares coordinates (fitting its OBBs, RSS distances): past about
// 1e154 the squares overflow and its answers are wrong (measured on a car
// scaled by s against a human: Eigen "Jacobi" warnings from s = 1e153, a
// contact that is not there at 1e155). Scenes whose coordinates stay within
// this limit are scored; others are refused.
inline constexpr double kExactCoordinateLimit = 1e150;

using PairList = std::vector<std::pair<uint32_t, uint32_t>>;

// The mesh's own axis-aligned bounds (mesh non-empty).
Aabb mesh_bounds(const Mesh& mesh);

// The exact answer for one frame: object i is mesh mesh_of_object[i] (an id
// in `meshes`, with local bounds local_bounds[that id]) at poses[i]. Pairs
// whose world boxes overlap (sweep and prune on x) get the FCL test.
struct ExactFrame {
  PairList contacts;  // (a, b), a < b, sorted
  uint64_t tested = 0;
};
ExactFrame exact_frame(std::span<const Pose> poses, std::span<const int> mesh_of_object,
                       std::span<const Aabb> local_bounds, ExactMeshes& meshes);
// The candidate pairs alone (world boxes overlap), sorted.
PairList overlapping_bounds(std::span<const Pose> poses, std::span<const int> mesh_of_object,
                            std::span<const Aabb> local_bounds);

}  // namespace octbake::scene
