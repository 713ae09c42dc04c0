#include "import.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <Eigen/Geometry>
#include <assimp/Importer.hpp>
#include <cmath>
#include <exception>
#include <filesystem>
#include <fstream>
#include <limits>

namespace octbake {
namespace {

Error refuse(ErrorCode code, std::string reason) { return Error{code, std::move(reason)}; }

// Assimp's messages can span lines; the CLI prints one line per failure.
std::string one_line(std::string s) {
  for (char& ch : s)
    if (ch == '\n' || ch == '\r' || ch == '\t') ch = ' ';
  while (!s.empty() && s.back() == ' ') s.pop_back();
  while (!s.empty() && s.front() == ' ') s.erase(s.begin());
  return s.empty() ? std::string("unreadable or unsupported file") : s;
}

Eigen::Matrix4d to_eigen(const aiMatrix4x4& m) {
  Eigen::Matrix4d r;
  r << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4;
  return r;
}

bool finite(const Eigen::Vector3d& p) { return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z()); }

// Appends the triangles of one mesh instance, placed by `to_world`. Only the
// vertices that triangles use are kept, so point/line-only parts of a mixed
// mesh do not widen the bounds.
Result<bool> append_instance(const aiMesh& src, const Eigen::Matrix4d& to_world, Mesh& out) {
  constexpr uint32_t kUnused = std::numeric_limits<uint32_t>::max();
  std::vector<uint32_t> remap(src.mNumVertices, kUnused);
  for (unsigned f = 0; f < src.mNumFaces; ++f) {
    const aiFace& face = src.mFaces[f];
    if (face.mNumIndices != 3 || face.mIndices == nullptr) continue;  // points and lines
    std::array<uint32_t, 3> tri{};
    for (int k = 0; k < 3; ++k) {
      const unsigned v = face.mIndices[k];
      if (v >= src.mNumVertices || src.mVertices == nullptr) return refuse(ErrorCode::invalid_argument, "face index out of range");
      if (remap[v] == kUnused) {
        if (out.positions.size() >= kUnused) return refuse(ErrorCode::invalid_argument, "too many vertices");
        const aiVector3D& p = src.mVertices[v];
        const Eigen::Vector3d local(p.x, p.y, p.z);
        if (!finite(local)) return refuse(ErrorCode::invalid_argument, "NaN or infinite vertex coordinate");
        const Eigen::Vector3d world = (to_world * local.homogeneous()).hnormalized();
        if (!finite(world)) return refuse(ErrorCode::invalid_argument, "NaN or infinite vertex coordinate after node transform");
        remap[v] = static_cast<uint32_t>(out.positions.size());
        out.positions.push_back(world);
      }
      tri[k] = remap[v];
    }
    out.triangles.push_back(tri);
  }
  return true;
}

}  // namespace

Result<Mesh> import_mesh(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (!fs::exists(st)) return refuse(ErrorCode::not_found, "no such file");
  if (fs::is_directory(st)) return refuse(ErrorCode::invalid_argument, "is a directory, not a mesh file");
  if (!fs::is_regular_file(st)) return refuse(ErrorCode::invalid_argument, "not a regular file");
  if (!std::ifstream(path, std::ios::binary)) return refuse(ErrorCode::io_error, "cannot open for reading");
  if (fs::file_size(path, ec) == 0 && !ec) return refuse(ErrorCode::invalid_argument, "empty file");

  // No DefaultLogger is created, so assimp logs nothing. Our own walk of the
  // node graph applies the transforms (PreTransformVertices would also merge
  // and reorder meshes); degenerate triangles are kept on purpose.
  Assimp::Importer importer;
  const aiScene* scene = nullptr;
  try {
    scene = importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_ValidateDataStructure);
  } catch (const std::exception& e) {
    return refuse(ErrorCode::invalid_argument, one_line(e.what()));
  } catch (...) {
    return refuse(ErrorCode::invalid_argument, "unreadable or unsupported file");
  }
  if (scene == nullptr) return refuse(ErrorCode::invalid_argument, one_line(importer.GetErrorString()));
  if (scene->mNumMeshes == 0 || scene->mMeshes == nullptr || scene->mRootNode == nullptr)
    return refuse(ErrorCode::invalid_argument, "empty scene (no meshes)");

  struct Pending {
    const aiNode* node;
    Eigen::Matrix4d to_world;
    int level;
  };
  constexpr int kMaxNodeDepth = 1024;  // a malformed file could make a cycle
  Mesh mesh;
  std::vector<Pending> stack{{scene->mRootNode, to_eigen(scene->mRootNode->mTransformation), 0}};
  while (!stack.empty()) {
    const Pending at = stack.back();
    stack.pop_back();
    if (at.level > kMaxNodeDepth) return refuse(ErrorCode::invalid_argument, "node graph too deep (cycle?)");
    for (unsigned i = 0; i < at.node->mNumMeshes; ++i) {
      const unsigned m = at.node->mMeshes[i];
      if (m >= scene->mNumMeshes || scene->mMeshes[m] == nullptr) return refuse(ErrorCode::invalid_argument, "node refers to a missing mesh");
      if (Result<bool> r = append_instance(*scene->mMeshes[m], at.to_world, mesh); !r) return r.error();
    }
    // Children pushed in reverse so they are visited in file order: the
    // vertex order of the result then follows the file.
    for (unsigned i = at.node->mNumChildren; i-- > 0;) {
      const aiNode* child = at.node->mChildren[i];
      if (child != nullptr) stack.push_back({child, at.to_world * to_eigen(child->mTransformation), at.level + 1});
    }
  }
  if (mesh.triangles.empty()) return refuse(ErrorCode::invalid_argument, "no triangles (points or lines only)");
  return mesh;
}

}  // namespace octbake
