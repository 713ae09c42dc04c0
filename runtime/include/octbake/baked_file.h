// Read-only memory-mapped baked files (.oct files and packs).
//
// open() maps the file and verifies it completely before anything is trusted:
// identifier, format version, the FlatBuffers verifier, every count, size and
// offset. Level data is decompressed lazily by load(), only up to the depth
// asked for, and each level's decoded size is checked against the header
// before and after decompression (no decompression bombs).
//
// Thread safety: after open()/from_bytes() returns, a BakedFile is immutable
// apart from its atomic work counters, so any number of threads may call its
// const members (load, decode_level, trees, find, stats) at once, and share
// the ObjectTrees load() returns read-only. Moving or destroying it needs
// exclusive access (and no LevelCache still registered on it). A ModelLibrary
// opens files lazily: use one per thread, or guard it.
#pragma once
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "octbake/format.h"
#include "octbake/object_tree.h"
#include "octbake/result.h"
#include "octbake/export.h"

namespace octbake {

// Work counters, so tests can assert how much a load did.
struct LoadStats {
  uint64_t files_opened = 0;        // BakedFile::open calls that succeeded
  uint64_t bytes_mapped = 0;        // their file sizes (from_bytes maps nothing)
  uint64_t levels_decoded = 0;      // levels produced by load() and decode_level()
  uint64_t bytes_decompressed = 0;  // decoded bytes of those levels (raw ones copied)
};

class OCTBAKE_API BakedFile {
 public:
  // Errors: not_found (no such file), io_error, truncated (shorter than its
  // size prefix, or than any octbake file), bad_identifier, unsupported_version
  // (newer than kFormatVersion), corrupt (verifier or a count/size check).
  static Result<BakedFile> open(const std::string& path);
  // Same checks for bytes already in memory (tests, fuzzing); `label` names
  // them in messages. The bytes must outlive the BakedFile (misaligned bytes
  // are copied once, since the header holds doubles).
  static Result<BakedFile> from_bytes(std::span<const uint8_t> bytes, const std::string& label);

  BakedFile(BakedFile&&) noexcept;
  BakedFile& operator=(BakedFile&&) noexcept;
  ~BakedFile();

  const std::string& path() const;
  uint32_t format_version() const;
  const std::string& baker_version() const;
  // Headers of every tree, decoded from the mapping without decompressing.
  const std::vector<TreeInfo>& trees() const;
  // Index of the tree named `name`, or not_found.
  Result<size_t> find(const std::string& name) const;
  // Decodes tree `index` down to min(depth, baked depth): levels 1..depth only.
  // Errors: invalid_argument (index out of range, depth < 0),
  // decompress_failed (broken frame, or one that lies about its size),
  // corrupt (decoded masks disagree with the header's box counts).
  Result<ObjectTree> load(size_t index, int depth) const;
  // Level `level` (1..baked depth) of tree `index` alone: the child masks of
  // depth level-1, one byte per box of that depth, verified exactly as load()
  // verifies it (size before and after decompression, box count). The
  // streaming decoder of LevelCache. Errors: invalid_argument (index or level
  // out of range), decompress_failed, corrupt.
  Result<std::vector<uint8_t>> decode_level(size_t index, int level) const;
  // A snapshot of the counters (they may move on while other threads decode).
  LoadStats stats() const;

 private:
  struct Impl;
  explicit BakedFile(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// Models a scene names, from a folder of .oct files or from a pack, opening
// only the files that hold them.
class OCTBAKE_API ModelLibrary {
 public:
  // `source`: a folder (model "x" is "<folder>/x.oct", opened when first
  // asked for; a file holding a single tree of another name still serves it)
  // or a pack file (opened now, trees found by name). not_found when missing.
  static Result<ModelLibrary> open(const std::string& source);
  // Loads model `name` down to `depth` (clamped to its baked depth).
  Result<ObjectTree> load(const std::string& name, int depth);
  // Header of model `name` without decoding levels.
  Result<TreeInfo> info(const std::string& name);
  LoadStats stats() const;

 private:
  std::string source_;
  bool is_pack_ = false;
  std::vector<std::pair<std::string, BakedFile>> files_;  // opened, by path
  Result<BakedFile*> file_for(const std::string& name, size_t* index);
};

}  // namespace octbake
