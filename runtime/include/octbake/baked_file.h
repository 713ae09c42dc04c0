// Read-only memory-mapped baked files (.oct files and packs).
//
// open() maps the file and verifies it completely before anything is trusted:
// identifier, format version, the FlatBuffers verifier, every count, size and
// offset. Level data is decompressed lazily by load(), only up to the depth
// asked for, and each level's decoded size is checked against the header
// before and after decompression (no decompression bombs).
#pragma once
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "octbake/format.h"
#include "octbake/object_tree.h"
#include "octbake/result.h"

namespace octbake {

// Work counters, so tests can assert how much a load did.
struct LoadStats {
  uint64_t files_opened = 0;
  uint64_t bytes_mapped = 0;
  uint64_t levels_decoded = 0;
  uint64_t bytes_decompressed = 0;
};

class BakedFile {
 public:
  static Result<BakedFile> open(const std::string& path);
  // Same checks for bytes already in memory (tests, fuzzing). The bytes must
  // outlive the BakedFile.
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
  Result<ObjectTree> load(size_t index, int depth) const;
  const LoadStats& stats() const;

 private:
  struct Impl;
  explicit BakedFile(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// Models a scene names, from a folder of .oct files or from a pack, opening
// only the files that hold them.
class ModelLibrary {
 public:
  // `source`: a folder (model "x" is "<folder>/x.oct") or a pack file.
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
