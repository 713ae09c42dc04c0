// Encoding and decoding of baked files (schema/octbake.fbs), in memory.
// The baker writes what encode_file() returns; BakedFile reads it mapped.
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "octbake/octree.h"
#include "octbake/result.h"
#include "octbake/export.h"

namespace octbake {

// Format-fixing: bump on any change to the schema's meaning. Readers accept
// every version up to this one and refuse newer ones.
constexpr uint32_t kFormatVersion = 1;
constexpr const char* kFileIdentifier = "OCTB";
// Deepest level a file may hold: 8^12 boxes is far past any useful tree.
constexpr int kMaxDepth = 12;

enum class Compression : uint8_t { none = 0, zstd = 1 };

struct BakeOptions {
  int depth = 6;  // 1..12
  Occupancy occupancy = Occupancy::surface;
  Compression compression = Compression::zstd;
  int compression_level = 19;
  bool operator==(const BakeOptions&) const = default;
};

// Header of one tree: everything readable without decompressing.
struct TreeInfo {
  std::string name;
  std::string source_hash;  // hex
  BakeOptions options;
  Aabb bounds;
  int depth = 0;
  uint64_t triangle_count = 0;
  uint64_t vertex_count = 0;
  std::vector<uint64_t> box_count;     // per level 0..depth
  std::vector<uint64_t> stored_bytes;  // per level, as stored (compressed)
  std::vector<uint64_t> raw_bytes;     // per level, decoded
};

struct TreeToEncode {
  std::string name;
  std::string source_hash;
  BakeOptions options;
  uint64_t triangle_count = 0;
  uint64_t vertex_count = 0;
  OctreeMasks masks;  // masks.depth() == options.depth
};

// Deterministic bytes for one or more trees (a pack when more than one): the
// same trees, baker version and libzstd version give the same bytes, for
// every `threads`. Each level is one zstd frame at options.compression_level,
// or raw when compression is none or the frame would not be smaller. Never
// more than `threads` compressions run at once: first the levels under 1 MiB,
// each a frame of one job, on the calling thread and up to
// threads - 1 helpers; then each larger level, in equal jobs whose count is
// fixed by the level's size (zstd's multithreaded mode, which writes the
// same frame for any worker count), up to `threads` jobs at once while the
// calling thread waits.
// Preconditions (asserted): at least one tree; unique, non-empty names;
// masks.depth() == options.depth in 1..kMaxDepth; masks[d].size() equal to
// the box count of depth d; finite bounds with min <= max; threads >= 1.
// Throws std::bad_alloc when zstd cannot get its memory or threads.
OCTBAKE_API std::vector<uint8_t> encode_file(std::span<const TreeToEncode> trees, const std::string& baker_version,
                                             int threads = 1);

// The most threads encode_file can keep busy on these trees: for the tree
// that has the most, the larger of its count of one-job levels and its most
// jobs in one level (1 when nothing is compressed).
OCTBAKE_API int encode_threads_useful(std::span<const TreeToEncode> trees);

}  // namespace octbake
