#include "import.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <Eigen/Geometry>
#include <assimp/DefaultIOSystem.h>
#include <assimp/Importer.hpp>
#include <cmath>
#include <algorithm>
#include <cctype>
#include <exception>
#include <filesystem>
#include <fstream>
#include <limits>
#include <new>
#include <numeric>
#include <string_view>

namespace octbake {
namespace {

Error refuse(ErrorCode code, std::string reason) { return Error{code, std::move(reason)}; }

// Assimp's messages can span lines; the CLI prints one line per failure.
// assimp catches its own exceptions and keeps only what(): a bad_alloc's is
// named for what it means.
std::string one_line(std::string s) {
  for (char& ch : s)
    if (ch == '\n' || ch == '\r' || ch == '\t') ch = ' ';
  while (!s.empty() && s.back() == ' ') s.pop_back();
  while (!s.empty() && s.front() == ' ') s.erase(s.begin());
  if (s == std::bad_alloc().what()) return "out of memory reading this file";
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
        // assimp reads single precision: a finite 1e300 in the file arrives as inf.
        if (!finite(local))
          return refuse(ErrorCode::invalid_argument,
                        "NaN or infinite vertex coordinate (assimp reads floats: past 3.4e38 in magnitude is infinite)");
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

// Joins exactly equal positions (assimp's JoinIdenticalVertices compares with
// an epsilon, which would move geometry, and it silently merges NaNs away).
// Sorting keeps the result independent of hash order.
void join_identical(Mesh& mesh) {
  const size_t n = mesh.positions.size();
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  auto less = [&](uint32_t a, uint32_t b) {
    const Eigen::Vector3d &p = mesh.positions[a], &q = mesh.positions[b];
    if (p.x() != q.x()) return p.x() < q.x();
    if (p.y() != q.y()) return p.y() < q.y();
    if (p.z() != q.z()) return p.z() < q.z();
    return a < b;
  };
  std::sort(order.begin(), order.end(), less);
  // New index = rank of the first occurrence, so output order follows input order.
  std::vector<uint32_t> first(n);
  for (size_t i = 0; i < n; ++i)
    first[order[i]] = (i > 0 && mesh.positions[order[i]] == mesh.positions[order[i - 1]]) ? first[order[i - 1]] : order[i];
  std::vector<uint32_t> remap(n);
  std::vector<Eigen::Vector3d> kept;
  for (size_t i = 0; i < n; ++i) {
    if (first[i] == i) {
      remap[i] = static_cast<uint32_t>(kept.size());
      kept.push_back(mesh.positions[i]);
    } else {
      remap[i] = remap[first[i]];
    }
  }
  for (auto& t : mesh.triangles)
    for (uint32_t& v : t) v = remap[v];
  mesh.positions = std::move(kept);
}

// assimp's OFF reader trusts the header's counts and allocates (and zeroes)
// that many vertices and faces before reading any: a 300-byte file can ask
// for 20 GB. Refuse counts the file is too small to hold (an ASCII vertex
// takes at least 6 bytes, a face at least 2).
Result<bool> check_off_header(const std::string& path, uintmax_t size) {
  std::ifstream in(path, std::ios::binary);
  std::string head(4096, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  std::vector<std::string> tokens;
  size_t i = 0;
  while (i < head.size() && tokens.size() < 3) {
    const unsigned char ch = static_cast<unsigned char>(head[i]);
    if (ch == '#') {
      while (i < head.size() && head[i] != '\n') ++i;
    } else if (std::isspace(ch)) {
      ++i;
    } else {
      const size_t start = i;
      while (i < head.size() && !std::isspace(static_cast<unsigned char>(head[i]))) ++i;
      tokens.push_back(head.substr(start, i - start));
    }
  }
  if (tokens.size() < 3 || tokens[0].find("OFF") == std::string::npos) return true;  // not OFF: assimp decides
  auto count = [](const std::string& t) {
    uintmax_t v = 0;
    for (char ch : t) {
      if (ch < '0' || ch > '9') break;
      v = std::min<uintmax_t>(v * 10 + uintmax_t(ch - '0'), std::numeric_limits<uint32_t>::max() * uintmax_t{16});
    }
    return v;
  };
  const uintmax_t vertices = count(tokens[1]), faces = count(tokens[2]);
  if (vertices * 6 > size || faces * 2 > size)
    return refuse(ErrorCode::invalid_argument, "OFF header claims " + tokens[1] + " vertices and " + tokens[2] +
                                                   " faces, more than the file can hold");
  return true;
}

// assimp's PLY reader, given a header that never ends (a file cut short
// inside its header, or "end_header" mangled or run into the token before or
// the data after), crashes or reads past the end forever. A header is a few
// lines: refuse a PLY (first three bytes "ply" in any case, as assimp
// checks) whose first MiB holds no line whose first token is "end_header",
// read as assimp reads it: lines end at CR or LF, blanks before the token,
// and a blank, form feed or NUL after it.
Result<bool> check_ply_header(const std::string& path) {
  constexpr size_t kMaxHeader = 1 << 20;
  std::ifstream in(path, std::ios::binary);
  std::string head(kMaxHeader, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  auto lower = [](char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); };
  if (head.size() < 3 || lower(head[0]) != 'p' || lower(head[1]) != 'l' || lower(head[2]) != 'y') return true;
  constexpr std::string_view kEnd = "end_header";
  auto blank = [](char c) { return c == ' ' || c == '\t'; };
  for (size_t at = 0; at < head.size();) {
    while (at < head.size() && blank(head[at])) ++at;
    if (head.compare(at, kEnd.size(), kEnd) == 0) {
      const size_t after = at + kEnd.size();
      if (after == head.size() || blank(head[after]) || head[after] == '\r' || head[after] == '\n' ||
          head[after] == '\f' || head[after] == '\0')
        return true;
    }
    at = head.find_first_of("\r\n", at);
    if (at == std::string::npos) break;
    ++at;
  }
  return refuse(ErrorCode::invalid_argument, head.size() < kMaxHeader
                                                 ? "PLY header has no end_header line (file cut short or damaged)"
                                                 : "PLY header has no end_header line in its first MiB");
}

// assimp's own file access, recording each file it opens: an OBJ's .mtl, a
// glTF's .bin are read through here, so a build system can depend on them.
class RecordingIOSystem : public Assimp::DefaultIOSystem {
 public:
  explicit RecordingIOSystem(std::vector<std::string>* files) : files_(files) {}
  Assimp::IOStream* Open(const char* file, const char* mode = "rb") override {
    Assimp::IOStream* stream = DefaultIOSystem::Open(file, mode);
    if (stream != nullptr && files_ != nullptr) {
      std::error_code ec;
      std::filesystem::path p = std::filesystem::absolute(file, ec);
      const std::string name = ec ? std::string(file) : p.lexically_normal().string();
      if (std::find(files_->begin(), files_->end(), name) == files_->end()) files_->push_back(name);
    }
    return stream;
  }

 private:
  std::vector<std::string>* files_;
};

}  // namespace

Result<Mesh> prepare_mesh(const std::vector<Eigen::Vector3d>& positions,
                          const std::vector<std::array<uint32_t, 3>>& triangles) {
  // The same path as a file's mesh: one instance placed by the identity.
  constexpr uint32_t kUnused = std::numeric_limits<uint32_t>::max();
  if (positions.size() >= kUnused) return refuse(ErrorCode::invalid_argument, "too many vertices");
  std::vector<uint32_t> remap(positions.size(), kUnused);
  Mesh mesh;
  mesh.triangles.reserve(triangles.size());
  for (const auto& t : triangles) {
    std::array<uint32_t, 3> tri{};
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = t[k];
      if (v >= positions.size()) return refuse(ErrorCode::invalid_argument, "triangle index out of range");
      if (remap[v] == kUnused) {
        if (!finite(positions[v])) return refuse(ErrorCode::invalid_argument, "NaN or infinite vertex coordinate");
        remap[v] = static_cast<uint32_t>(mesh.positions.size());
        mesh.positions.push_back(positions[v]);
      }
      tri[k] = remap[v];
    }
    mesh.triangles.push_back(tri);
  }
  if (mesh.triangles.empty()) return refuse(ErrorCode::invalid_argument, "no triangles");
  join_identical(mesh);
  return mesh;
}

Result<Mesh> import_mesh(const std::string& path, std::vector<std::string>* files_read) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (!fs::exists(st)) return refuse(ErrorCode::not_found, "no such file");
  if (fs::is_directory(st)) return refuse(ErrorCode::invalid_argument, "is a directory, not a mesh file");
  if (!fs::is_regular_file(st)) return refuse(ErrorCode::invalid_argument, "not a regular file");
  if (!std::ifstream(path, std::ios::binary)) return refuse(ErrorCode::io_error, "cannot open for reading");
  const uintmax_t size = fs::file_size(path, ec);
  if (ec) return refuse(ErrorCode::io_error, "cannot read the file size");
  if (size == 0) return refuse(ErrorCode::invalid_argument, "empty file");
  if (Result<bool> r = check_off_header(path, size); !r) return r.error();
  if (Result<bool> r = check_ply_header(path); !r) return r.error();

  // No DefaultLogger is created, so assimp logs nothing. Our own walk of the
  // node graph applies the transforms (PreTransformVertices would also merge
  // and reorder meshes); degenerate triangles are kept on purpose; identical
  // vertices are joined afterwards, exactly (join_identical).
  Assimp::Importer importer;
  importer.SetIOHandler(new RecordingIOSystem(files_read));  // owned by the importer
  const aiScene* scene = nullptr;
  try {
    scene = importer.ReadFile(path, aiProcess_Triangulate | aiProcess_ValidateDataStructure);
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
  join_identical(mesh);
  return mesh;
}

}  // namespace octbake
