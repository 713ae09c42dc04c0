#include "exact.h"

#include <fcl/narrowphase/collision.h>

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

}  // namespace octbake::scene
