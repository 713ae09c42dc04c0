// octbake::baker — baking in process, the library behind the `octbake` tool.
//
//   find_package(octbake REQUIRED)                  # or add_subdirectory(octbake)
//   target_link_libraries(tool PRIVATE octbake::baker)
//
//   #include <octbake/baker.h>
//   octbake::BakeOptions options;                   // depth 6, surface, zstd:19
//   options.depth = 5;
//   auto bytes = octbake::bake_to_memory(vertices, indices, "crate", options);
//   if (!bytes) { /* bytes.error().code, bytes.error().message */ }
//   auto file = octbake::BakedFile::from_bytes(*bytes, "crate");   // the runtime reads it
//
// The result of every call is the same as `octbake` gives for the same mesh
// and options (docs/interface.md, sections "octbake" and "The baked file"):
// bake_file(path, out, options) writes byte for byte what
// `octbake -o DIR -d ... FILE` writes. Calls are thread safe (no shared
// state) and deterministic. No exception leaves them; failures are an Error:
//   not_found / io_error   a file that cannot be read or written,
//   invalid_argument       a malformed mesh or out-of-range option,
// with a message that names the file (or "mesh arrays") and the reason.
// Mesh files are read by assimp (any format it reads); the runtime library
// never needs assimp, and this library links it privately.
#pragma once
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "octbake/baker_export.h"
#include "octbake/format.h"
#include "octbake/octree.h"
#include "octbake/result.h"

namespace octbake {

// A triangle mesh in its own (local) coordinates: the input of a bake.
struct Mesh {
  std::vector<Eigen::Vector3d> positions;
  std::vector<std::array<uint32_t, 3>> triangles;  // indices into positions
};

// Reads the mesh file at `path` as the baker does: triangulated, node
// transforms applied in double, only vertices that triangles use kept,
// exactly identical vertices joined, degenerate triangles kept.
// When `files_read` is given, it receives every file the importer opened
// (absolute, normalised, first-opened order, no duplicates): the mesh file
// itself and what it refers to (an OBJ's .mtl, a glTF's .bin) — what a
// build system must watch to know when to rebake.
// Errors: not_found (no such file), io_error (unreadable), invalid_argument
// (directory, empty, malformed, points or lines only, NaN or infinite
// coordinates, headers that claim more data than the file holds, a PLY
// header without end_header, out of memory).
// The importer (assimp) runs in the calling process: a malformed file that
// crashes or hangs assimp crashes or hangs the caller. The `octbake` tool
// imports each file in a child process instead; an app that reads untrusted
// files can do the same (run `octbake` on them, or call this in a child).
OCTBAKE_BAKER_API Result<Mesh> load_mesh(const std::string& path, std::vector<std::string>* files_read = nullptr);

// A mesh from flat arrays: `vertices` holds x, y, z per vertex, `indices`
// three vertex numbers per triangle. Checked, then prepared exactly as
// load_mesh prepares a file's mesh (unused vertices dropped, identical ones
// joined). Errors (invalid_argument): a vertex count not a multiple of 3, an
// index count not a multiple of 3 or zero, an index out of range, a NaN or
// infinite coordinate.
OCTBAKE_BAKER_API Result<Mesh> mesh_from_arrays(std::span<const double> vertices, std::span<const uint32_t> indices);
OCTBAKE_BAKER_API Result<Mesh> mesh_from_arrays(std::span<const float> vertices, std::span<const uint32_t> indices);

// The ObjectTree of `mesh` (root = its axis-aligned bounds) built to
// options.depth with options.occupancy (compression does not matter here).
// Errors (invalid_argument): depth outside 1..kMaxDepth, a mesh without
// triangles or with an index out of range.
OCTBAKE_BAKER_API Result<OctreeMasks> bake_masks(const Mesh& mesh, const BakeOptions& options);

// A complete baked file in memory, holding one tree named `name`, for
// BakedFile::from_bytes or to be written anywhere. `source_hash` is recorded
// in the file (the CLI records the XXH3-128 of the mesh file; pass "" to
// record the hash of the mesh's own positions and triangles). Errors: as
// bake_masks, plus invalid_argument for an empty name or a compression level
// outside 1..22 with zstd.
OCTBAKE_BAKER_API Result<std::vector<uint8_t>> bake_to_memory(const Mesh& mesh, const std::string& name,
                                                              const BakeOptions& options,
                                                              const std::string& source_hash = "");
// The same from flat arrays (see mesh_from_arrays).
OCTBAKE_BAKER_API Result<std::vector<uint8_t>> bake_to_memory(std::span<const double> vertices,
                                                              std::span<const uint32_t> indices,
                                                              const std::string& name, const BakeOptions& options);

// Bakes the mesh file `mesh_path` into `out_path` (tree named after the
// file's stem, source hash = XXH3-128 of the file), written atomically (a
// temp file renamed into place: readers see the old file or the new one).
// Always bakes (the CLI's up-to-date check is the CLI's). `files_read` as
// load_mesh. Returns the number of bytes written.
OCTBAKE_BAKER_API Result<uint64_t> bake_file(const std::string& mesh_path, const std::string& out_path,
                                             const BakeOptions& options,
                                             std::vector<std::string>* files_read = nullptr);

// The source hash octbake records for a mesh file: hex XXH3-128 of its bytes
// (32 lowercase digits, canonical big endian). Only this file is hashed, not
// the files it refers to. Errors: not_found, io_error (message names the path).
OCTBAKE_BAKER_API Result<std::string> source_hash(const std::string& path);

// The version recorded as "baker version" in every file this library writes
// (the project version, octbake/version.h kLibraryVersion).
OCTBAKE_BAKER_API const char* baker_version();

}  // namespace octbake
