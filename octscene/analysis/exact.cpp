#include "exact.h"

#include <fcl/narrowphase/collision.h>

#include <algorithm>
#include <filesystem>

namespace octbake::scene {

std::string find_mesh(const std::string& dir, const std::string& model) {
  static const char* const kExtensions[] = {".obj", ".ply", ".stl", ".off", ".gltf", ".glb", ".dae", ".fbx"};
  for (const char* ext : kExtensions) {
    const std::filesystem::path p = std::filesystem::path(dir) / (model + ext);
    std::error_code ec;
    if (std::filesystem::is_regular_file(p, ec)) return p.string();
  }
  return {};
}

std::shared_ptr<Bvh> build_bvh(const Mesh& mesh, double scale) {
  std::vector<fcl::Vector3d> points;
  points.reserve(mesh.positions.size());
  for (const Eigen::Vector3d& p : mesh.positions) points.push_back(scale * p);
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
  auto bvh = std::make_shared<Bvh>();
  bvh->beginModel(static_cast<int>(triangles.size()), static_cast<int>(points.size()));
  bvh->addSubModel(points, triangles);
  bvh->endModel();
  bvh->computeLocalAABB();
  return bvh;
}

fcl::Transform3d to_fcl(const Pose& pose) {
  fcl::Transform3d t = fcl::Transform3d::Identity();
  t.linear() = pose.rotation.normalized().toRotationMatrix();
  t.translation() = pose.position;
  return t;
}

bool bvh_collide(const Bvh& a, const Pose& pose_a, const Bvh& b, const Pose& pose_b) {
  const fcl::CollisionRequestd request(/*num_max_contacts=*/1, /*enable_contact=*/false);
  fcl::CollisionResultd result;
  fcl::collide(&a, to_fcl(pose_a), &b, to_fcl(pose_b), request, result);
  return result.isCollision();
}

int ExactMeshes::add(Mesh mesh) {
  meshes_.push_back(std::move(mesh));
  return static_cast<int>(meshes_.size()) - 1;
}

const Bvh& ExactMeshes::bvh(int model, double scale) {
  auto& slot = bvhs_[{model, scale}];
  if (!slot) slot = build_bvh(meshes_[model], scale);
  return *slot;
}

bool ExactMeshes::collide(int model_a, const Pose& a, int model_b, const Pose& b) {
  return bvh_collide(bvh(model_a, a.scale), a, bvh(model_b, b.scale), b);
}

Aabb mesh_bounds(const Mesh& mesh) {
  Aabb box{mesh.positions[0], mesh.positions[0]};
  for (const Eigen::Vector3d& p : mesh.positions) {
    box.min = box.min.cwiseMin(p);
    box.max = box.max.cwiseMax(p);
  }
  return box;
}

PairList overlapping_bounds(std::span<const Pose> poses, std::span<const int> mesh_of_object,
                            std::span<const Aabb> local_bounds) {
  const size_t n = poses.size();
  std::vector<Aabb> world(n);
  std::vector<uint32_t> order(n);
  for (size_t i = 0; i < n; ++i) {
    world[i] = world_bounds(place(local_bounds[mesh_of_object[i]], poses[i]));
    order[i] = static_cast<uint32_t>(i);
  }
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return world[a].min.x() < world[b].min.x(); });
  PairList out;
  for (size_t k = 0; k < n; ++k) {
    const uint32_t i = order[k];
    for (size_t l = k + 1; l < n && world[order[l]].min.x() <= world[i].max.x(); ++l) {
      const uint32_t j = order[l];
      if (world[i].min.y() > world[j].max.y() || world[j].min.y() > world[i].max.y()) continue;
      if (world[i].min.z() > world[j].max.z() || world[j].min.z() > world[i].max.z()) continue;
      out.emplace_back(std::min(i, j), std::max(i, j));
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

ExactFrame exact_frame(std::span<const Pose> poses, std::span<const int> mesh_of_object,
                       std::span<const Aabb> local_bounds, ExactMeshes& meshes) {
  ExactFrame out;
  for (const auto& [a, b] : overlapping_bounds(poses, mesh_of_object, local_bounds)) {
    ++out.tested;
    if (meshes.collide(mesh_of_object[a], poses[a], mesh_of_object[b], poses[b])) out.contacts.emplace_back(a, b);
  }
  return out;
}

}  // namespace octbake::scene
