// The public baking API (octbake/baker.h), over the baker's import, tree
// building and file writing. The CLI (bake.cpp) bakes through it too.
#include "octbake/baker.h"

#include <bit>
#include <cmath>
#include <exception>
#include <filesystem>
#include <new>

#include "build_tree.h"
#include "import.h"
#include "write.h"

namespace octbake {
namespace {

Error with_label(const Error& e, const std::string& label) { return Error{e.code, label + ": " + e.message}; }

template <class Real>
Result<Mesh> from_arrays(std::span<const Real> vertices, std::span<const uint32_t> indices) {
  const std::string label = "mesh arrays";
  if (vertices.size() % 3 != 0)
    return Error{ErrorCode::invalid_argument, label + ": vertex array size " + std::to_string(vertices.size()) +
                                                  " is not a multiple of 3 (x, y, z per vertex)"};
  if (indices.empty() || indices.size() % 3 != 0)
    return Error{ErrorCode::invalid_argument, label + ": index array size " + std::to_string(indices.size()) +
                                                  " is not a positive multiple of 3 (three per triangle)"};
  std::vector<Eigen::Vector3d> positions(vertices.size() / 3);
  for (size_t i = 0; i < positions.size(); ++i)
    positions[i] = {double(vertices[3 * i]), double(vertices[3 * i + 1]), double(vertices[3 * i + 2])};
  std::vector<std::array<uint32_t, 3>> triangles(indices.size() / 3);
  for (size_t t = 0; t < triangles.size(); ++t) triangles[t] = {indices[3 * t], indices[3 * t + 1], indices[3 * t + 2]};
  auto mesh = prepare_mesh(positions, triangles);
  if (!mesh) return with_label(mesh.error(), label);
  return mesh;
}

// XXH3-128 of the mesh as little-endian bytes: positions (IEEE doubles),
// then triangles (uint32): the same on every machine.
std::string mesh_hash(const Mesh& mesh) {
  std::vector<uint8_t> bytes;
  bytes.reserve(mesh.positions.size() * 24 + mesh.triangles.size() * 12);
  auto put = [&](uint64_t v, int n) {
    for (int i = 0; i < n; ++i) bytes.push_back(static_cast<uint8_t>(v >> (8 * i)));
  };
  for (const Eigen::Vector3d& p : mesh.positions)
    for (int a = 0; a < 3; ++a) put(std::bit_cast<uint64_t>(p[a]), 8);
  for (const auto& t : mesh.triangles)
    for (uint32_t v : t) put(v, 4);
  return hash_bytes(bytes);
}

Result<bool> check_options(const BakeOptions& options) {
  if (options.depth < 1 || options.depth > kMaxDepth)
    return Error{ErrorCode::invalid_argument, "depth " + std::to_string(options.depth) + " outside 1.." +
                                                  std::to_string(kMaxDepth)};
  if (options.compression == Compression::zstd && (options.compression_level < 1 || options.compression_level > 22))
    return Error{ErrorCode::invalid_argument,
                 "zstd level " + std::to_string(options.compression_level) + " outside 1..22"};
  if (options.compression != Compression::zstd && options.compression != Compression::none)
    return Error{ErrorCode::invalid_argument, "unknown compression"};
  if (options.occupancy != Occupancy::surface && options.occupancy != Occupancy::solid &&
      options.occupancy != Occupancy::vertices)
    return Error{ErrorCode::invalid_argument, "unknown occupancy mode"};
  return true;
}

Result<bool> check_mesh(const Mesh& mesh) {
  if (mesh.triangles.empty()) return Error{ErrorCode::invalid_argument, "mesh has no triangles"};
  for (const auto& t : mesh.triangles)
    for (uint32_t v : t)
      if (v >= mesh.positions.size()) return Error{ErrorCode::invalid_argument, "triangle index out of range"};
  for (const Eigen::Vector3d& p : mesh.positions)
    if (!p.allFinite()) return Error{ErrorCode::invalid_argument, "NaN or infinite vertex coordinate"};
  return true;
}

}  // namespace

Result<Mesh> load_mesh(const std::string& path, std::vector<std::string>* files_read) {
  try {
    auto mesh = import_mesh(path, files_read);
    if (!mesh) return with_label(mesh.error(), path);
    return mesh;
  } catch (const std::bad_alloc&) {  // a huge file, or a malformed one that asks for too much
    return Error{ErrorCode::invalid_argument, path + ": out of memory reading this file"};
  } catch (const std::exception& e) {
    return Error{ErrorCode::invalid_argument, path + ": " + e.what()};
  }
}

Result<Mesh> mesh_from_arrays(std::span<const double> vertices, std::span<const uint32_t> indices) {
  return from_arrays(vertices, indices);
}
Result<Mesh> mesh_from_arrays(std::span<const float> vertices, std::span<const uint32_t> indices) {
  return from_arrays(vertices, indices);
}

Result<OctreeMasks> bake_masks(const Mesh& mesh, const BakeOptions& options) {
  if (auto ok = check_options(options); !ok) return ok.error();
  if (auto ok = check_mesh(mesh); !ok) return ok.error();
  try {
    return build_tree(mesh, options.depth, options.occupancy);
  } catch (const std::exception& e) {
    return Error{ErrorCode::invalid_argument, std::string("cannot build the tree: ") + e.what()};
  }
}

Result<std::vector<uint8_t>> bake_to_memory(const Mesh& mesh, const std::string& name, const BakeOptions& options,
                                            const std::string& source_hash) {
  if (name.empty()) return Error{ErrorCode::invalid_argument, "empty tree name"};
  auto masks = bake_masks(mesh, options);
  if (!masks) return masks.error();
  TreeToEncode tree;
  tree.name = name;
  tree.source_hash = source_hash.empty() ? mesh_hash(mesh) : source_hash;
  tree.options = options;
  tree.triangle_count = mesh.triangles.size();
  tree.vertex_count = mesh.positions.size();
  tree.masks = std::move(*masks);
  try {
    return encode_file({&tree, 1}, baker_version());
  } catch (const std::exception& e) {
    return Error{ErrorCode::invalid_argument, std::string("cannot encode: ") + e.what()};
  }
}

Result<std::vector<uint8_t>> bake_to_memory(std::span<const double> vertices, std::span<const uint32_t> indices,
                                            const std::string& name, const BakeOptions& options) {
  auto mesh = mesh_from_arrays(vertices, indices);
  if (!mesh) return mesh.error();
  return bake_to_memory(*mesh, name, options);
}

Result<uint64_t> bake_file(const std::string& mesh_path, const std::string& out_path, const BakeOptions& options,
                           std::vector<std::string>* files_read) {
  auto hash = hash_file(mesh_path);
  if (!hash) return with_label(hash.error(), mesh_path);
  auto mesh = load_mesh(mesh_path, files_read);
  if (!mesh) return mesh.error();
  auto bytes = bake_to_memory(*mesh, std::filesystem::path(mesh_path).stem().string(), options, *hash);
  if (!bytes) return with_label(bytes.error(), mesh_path);
  auto written = write_file_atomic(out_path, *bytes);
  if (!written) return Error{written.error().code, "cannot write " + out_path + ": " + written.error().message};
  return written;
}

Result<std::string> source_hash(const std::string& path) {
  auto hash = hash_file(path);
  if (!hash) return with_label(hash.error(), path);
  return hash;
}

const char* baker_version() { return OCTBAKE_VERSION; }

}  // namespace octbake
