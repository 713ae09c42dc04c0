// BakedFile: verify a mapped baked file once, then decode levels on demand.
// ModelLibrary: find models in a folder of .oct files or in a pack.
#include "octbake/baked_file.h"

#include <zstd.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <unordered_set>

#include "mapped_file.h"
#include "octbake_generated.h"

namespace octbake {
namespace {

constexpr size_t kPrefixBytes = sizeof(flatbuffers::uoffset_t);
// Size prefix + root offset + identifier: nothing shorter is a baked file.
constexpr size_t kMinFileBytes = 3 * sizeof(flatbuffers::uoffset_t);
// zstd's densest block is 4 bytes of RLE standing for 128 KiB, so no frame
// decodes to more than this per stored byte. A level claiming more is lying,
// and refusing it at open keeps load() from allocating a bomb.
constexpr uint64_t kZstdMaxRatio = (128u << 10) / 4;

Error fail(ErrorCode code, const std::string& label, const std::string& why) {
  return Error{code, label + ": " + why};
}

std::string tree_label(const std::string& label, size_t index, const std::string& name) {
  return label + ": tree " + std::to_string(index) + (name.empty() ? "" : " \"" + name + "\"");
}

// File.format_version after checking only the bytes it occupies, so a newer
// file that this build cannot verify is still refused as a newer version.
std::optional<uint32_t> peek_format_version(std::span<const uint8_t> bytes) {
  flatbuffers::Verifier verifier(bytes.data(), bytes.size());
  const flatbuffers::uoffset_t root = verifier.VerifyOffset(kPrefixBytes);
  if (root == 0) return std::nullopt;
  // fb::File inherits Table privately; the table view is the same bytes.
  const auto* table = reinterpret_cast<const flatbuffers::Table*>(bytes.data() + kPrefixBytes + root);
  if (!table->VerifyTableStart(verifier) ||
      !table->VerifyField<uint32_t>(verifier, fb::File::VT_FORMAT_VERSION, sizeof(uint32_t))) {
    return std::nullopt;
  }
  return table->GetField<uint32_t>(fb::File::VT_FORMAT_VERSION, 0);
}

bool finite(const fb::Vec3& v) { return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z()); }

// Semantic checks on one verified tree; fills `info` from the header only.
std::optional<Error> read_tree(const fb::Tree& tree, const std::string& where, TreeInfo& info) {
  auto bad = [&](const std::string& why) { return Error{ErrorCode::corrupt, where + ": " + why}; };
  info.name = tree.name()->str();
  if (info.name.empty()) return bad("empty tree name");
  info.source_hash = tree.source_hash() ? tree.source_hash()->str() : std::string();
  const fb::BakeOptions& options = *tree.options();
  if (options.occupancy() > fb::Occupancy::MAX) return bad("unknown occupancy mode");
  if (options.compression() > fb::Compression::MAX) return bad("unknown compression");
  info.depth = tree.depth();
  if (info.depth < 1 || info.depth > kMaxDepth) {
    return bad("depth " + std::to_string(info.depth) + " outside 1.." + std::to_string(kMaxDepth));
  }
  if (options.depth() != info.depth) return bad("options depth differs from tree depth");
  info.options = {info.depth, static_cast<Occupancy>(options.occupancy()),
                  static_cast<Compression>(options.compression()), options.compression_level()};
  const fb::Vec3& lo = *tree.bounds_min();
  const fb::Vec3& hi = *tree.bounds_max();
  if (!finite(lo) || !finite(hi)) return bad("bounds not finite");
  if (!(lo.x() <= hi.x() && lo.y() <= hi.y() && lo.z() <= hi.z())) return bad("bounds min above max");
  info.bounds = {{lo.x(), lo.y(), lo.z()}, {hi.x(), hi.y(), hi.z()}};
  info.triangle_count = tree.triangle_count();
  info.vertex_count = tree.vertex_count();

  const auto& levels = *tree.levels();
  if (levels.size() != size_t(info.depth) + 1) {
    return bad(std::to_string(levels.size()) + " levels for depth " + std::to_string(info.depth));
  }
  for (int d = 0; d <= info.depth; ++d) {
    const fb::Level& level = *levels.Get(d);
    const uint64_t stored = level.data() ? level.data()->size() : 0;
    const std::string at = "level " + std::to_string(d) + ": ";
    if (level.compression() > fb::Compression::MAX) return bad(at + "unknown compression");
    if (d == 0) {
      if (level.box_count() != 1 || level.raw_size() != 0 || stored != 0) {
        return bad(at + "root level must be one box, no data");
      }
    } else {
      const uint64_t parents = info.box_count.back();
      if (level.raw_size() != parents) {
        return bad(at + "raw size " + std::to_string(level.raw_size()) + " but " + std::to_string(parents) +
                   " boxes above");
      }
      if (level.box_count() > 8 * parents) {
        return bad(at + std::to_string(level.box_count()) + " boxes under " + std::to_string(parents) + " parents");
      }
      if (level.compression() == fb::Compression::None && stored != level.raw_size()) {
        return bad(at + "stores " + std::to_string(stored) + " raw bytes, header says " +
                   std::to_string(level.raw_size()));
      }
      if (level.compression() == fb::Compression::Zstd && level.raw_size() > stored * kZstdMaxRatio) {
        return bad(at + "claims " + std::to_string(level.raw_size()) + " bytes from a " + std::to_string(stored) +
                   "-byte zstd frame");
      }
    }
    info.box_count.push_back(level.box_count());
    info.stored_bytes.push_back(stored);
    info.raw_bytes.push_back(level.raw_size());
  }
  return std::nullopt;
}

ZSTD_DCtx* decompressor() {
  // One per thread, reused: creating a context costs more than a small level.
  thread_local std::unique_ptr<ZSTD_DCtx, decltype(&ZSTD_freeDCtx)> dctx(ZSTD_createDCtx(), ZSTD_freeDCtx);
  return dctx.get();
}

}  // namespace

struct BakedFile::Impl {
  std::string label;
  detail::MappedFile mapping;         // empty for from_bytes
  std::vector<uint64_t> aligned_copy;  // from_bytes given misaligned bytes
  std::span<const uint8_t> bytes;
  const fb::File* root = nullptr;
  uint32_t format_version = 0;
  std::string baker_version;
  std::vector<TreeInfo> trees;
  // Updated by concurrent const reads, hence atomic (relaxed: plain counters,
  // they order nothing).
  std::atomic<uint64_t> files_opened{0}, bytes_mapped{0};
  mutable std::atomic<uint64_t> levels_decoded{0}, bytes_decompressed{0};

  // Everything before a byte of the file is trusted.
  std::optional<Error> verify() {
    const size_t size = bytes.size();
    if (size < kMinFileBytes) {
      return fail(ErrorCode::truncated, label,
                  std::to_string(size) + " bytes, shorter than any octbake file (" +
                      std::to_string(kMinFileBytes) + ")");
    }
    if (!flatbuffers::BufferHasIdentifier(bytes.data(), kFileIdentifier, /*size_prefixed=*/true)) {
      return fail(ErrorCode::bad_identifier, label, "not an octbake file (identifier is not \"OCTB\")");
    }
    const uint64_t said = flatbuffers::ReadScalar<flatbuffers::uoffset_t>(bytes.data()) + uint64_t{kPrefixBytes};
    if (said > size) {
      return fail(ErrorCode::truncated, label,
                  std::to_string(size) + " bytes, its header says " + std::to_string(said) + "; truncated copy?");
    }
    if (said < size) return fail(ErrorCode::corrupt, label, std::to_string(size - said) + " trailing bytes");
    if (size >= FLATBUFFERS_MAX_BUFFER_SIZE) return fail(ErrorCode::corrupt, label, "larger than 2 GiB");
    const std::optional<uint32_t> version = peek_format_version(bytes);
    if (!version) return fail(ErrorCode::corrupt, label, "root table damaged");
    if (*version > kFormatVersion) {
      return fail(ErrorCode::unsupported_version, label,
                  "format version " + std::to_string(*version) + ", this build reads up to " +
                      std::to_string(kFormatVersion) + "; rebake");
    }
    if (*version == 0) return fail(ErrorCode::corrupt, label, "format version 0");
    format_version = *version;
    // The per-version seam: everything above holds for every version (size
    // prefix, identifier, the version field); what follows is version 1's
    // layout. A version 2 adds its own read_vN/decode_level_vN pair here and
    // in decode_level(), and format.cpp's encode_file writes only the newest.
    switch (format_version) {
      case 1: return read_v1();
    }
    return fail(ErrorCode::unsupported_version, label, "format version " + std::to_string(format_version));
  }

  // Version 1: the FlatBuffers verifier, then every tree header's counts.
  std::optional<Error> read_v1() {
    const size_t size = bytes.size();
    flatbuffers::Verifier verifier(bytes.data(), size);
    if (!fb::VerifySizePrefixedFileBuffer(verifier)) {
      return fail(ErrorCode::corrupt, label, "fails FlatBuffers verification");
    }
    root = fb::GetSizePrefixedFile(bytes.data());
    baker_version = root->baker_version() ? root->baker_version()->str() : std::string();
    const auto& fb_trees = *root->trees();
    if (fb_trees.size() == 0) return fail(ErrorCode::corrupt, label, "holds no trees");
    std::unordered_set<std::string> names;
    trees.resize(fb_trees.size());
    for (size_t i = 0; i < fb_trees.size(); ++i) {
      const fb::Tree& tree = *fb_trees.Get(static_cast<flatbuffers::uoffset_t>(i));
      if (auto error = read_tree(tree, tree_label(label, i, tree.name()->str()), trees[i])) return error;
      if (!names.insert(trees[i].name).second) {
        return fail(ErrorCode::corrupt, label, "two trees named \"" + trees[i].name + "\"");
      }
    }
    return std::nullopt;
  }

  // Level d (>= 1) of tree t, decoded into exactly raw_size bytes and checked
  // against the box count of depth d.
  Result<std::vector<uint8_t>> decode_level(size_t t, int d) const {
    // Per-version seam (see verify()): only version 1 exists so far.
    return decode_level_v1(t, d);
  }

  Result<std::vector<uint8_t>> decode_level_v1(size_t t, int d) const {
    const TreeInfo& info = trees[t];
    const fb::Level& level = *root->trees()->Get(static_cast<flatbuffers::uoffset_t>(t))->levels()->Get(d);
    const std::string where = tree_label(label, t, info.name) + " level " + std::to_string(d);
    const uint64_t raw_size = info.raw_bytes[d];
    const uint8_t* src = level.data() ? level.data()->data() : nullptr;
    const size_t stored = info.stored_bytes[d];
    std::vector<uint8_t> out;
    if (level.compression() == fb::Compression::None) {
      out.assign(src, src + stored);  // verify() made stored == raw_size
    } else {
      const unsigned long long frame_size = ZSTD_getFrameContentSize(src, stored);
      if (frame_size == ZSTD_CONTENTSIZE_ERROR || frame_size == ZSTD_CONTENTSIZE_UNKNOWN) {
        return Error{ErrorCode::decompress_failed, where + ": not a zstd frame with a content size"};
      }
      if (frame_size != raw_size) {
        return Error{ErrorCode::decompress_failed, where + ": frame says " + std::to_string(frame_size) +
                                                       " bytes, header says " + std::to_string(raw_size)};
      }
      if (ZSTD_findFrameCompressedSize(src, stored) != stored) {
        return Error{ErrorCode::decompress_failed, where + ": not exactly one zstd frame"};
      }
      out.resize(raw_size);
      const size_t n = ZSTD_decompressDCtx(decompressor(), out.data(), out.size(), src, stored);
      if (ZSTD_isError(n)) return Error{ErrorCode::decompress_failed, where + ": " + ZSTD_getErrorName(n)};
      if (n != raw_size) {
        return Error{ErrorCode::decompress_failed,
                     where + ": decoded " + std::to_string(n) + " bytes, header says " + std::to_string(raw_size)};
      }
    }
    uint64_t boxes = 0;
    for (uint8_t m : out) boxes += std::popcount(m);
    if (boxes != info.box_count[d]) {
      return Error{ErrorCode::corrupt, where + ": masks hold " + std::to_string(boxes) + " boxes, header says " +
                                           std::to_string(info.box_count[d])};
    }
    levels_decoded.fetch_add(1, std::memory_order_relaxed);
    bytes_decompressed.fetch_add(out.size(), std::memory_order_relaxed);
    return out;
  }
};

BakedFile::BakedFile(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
BakedFile::BakedFile(BakedFile&&) noexcept = default;
BakedFile& BakedFile::operator=(BakedFile&&) noexcept = default;
BakedFile::~BakedFile() = default;

Result<BakedFile> BakedFile::open(const std::string& path) {
  Result<detail::MappedFile> mapping = detail::MappedFile::open(path);
  if (!mapping) return mapping.error();  // the message already names the path
  auto impl = std::make_unique<Impl>();
  impl->label = path;
  impl->mapping = std::move(mapping).value();
  impl->bytes = impl->mapping.bytes();
  if (auto error = impl->verify()) return *error;
  impl->files_opened = 1;
  impl->bytes_mapped = impl->bytes.size();
  return BakedFile(std::move(impl));
}

Result<BakedFile> BakedFile::from_bytes(std::span<const uint8_t> bytes, const std::string& label) {
  auto impl = std::make_unique<Impl>();
  impl->label = label;
  impl->bytes = bytes;
  // The header holds doubles read in place: they need 8-byte alignment.
  if (reinterpret_cast<uintptr_t>(bytes.data()) % alignof(uint64_t) != 0) {
    impl->aligned_copy.resize((bytes.size() + 7) / 8);
    std::memcpy(impl->aligned_copy.data(), bytes.data(), bytes.size());
    impl->bytes = {reinterpret_cast<const uint8_t*>(impl->aligned_copy.data()), bytes.size()};
  }
  if (auto error = impl->verify()) return *error;
  return BakedFile(std::move(impl));
}

const std::string& BakedFile::path() const { return impl_->label; }
uint32_t BakedFile::format_version() const { return impl_->format_version; }
const std::string& BakedFile::baker_version() const { return impl_->baker_version; }
const std::vector<TreeInfo>& BakedFile::trees() const { return impl_->trees; }
LoadStats BakedFile::stats() const {
  const auto get = [](const std::atomic<uint64_t>& n) { return n.load(std::memory_order_relaxed); };
  return {get(impl_->files_opened), get(impl_->bytes_mapped), get(impl_->levels_decoded),
          get(impl_->bytes_decompressed)};
}

Result<size_t> BakedFile::find(const std::string& name) const {
  for (size_t i = 0; i < impl_->trees.size(); ++i) {
    if (impl_->trees[i].name == name) return i;
  }
  return Error{ErrorCode::not_found, impl_->label + ": no tree \"" + name + "\""};
}

Result<ObjectTree> BakedFile::load(size_t index, int depth) const {
  if (index >= impl_->trees.size()) {
    return Error{ErrorCode::invalid_argument, impl_->label + ": no tree " + std::to_string(index)};
  }
  if (depth < 0) return Error{ErrorCode::invalid_argument, impl_->label + ": negative depth"};
  const TreeInfo& info = impl_->trees[index];
  OctreeMasks masks;
  masks.bounds = info.bounds;
  const int n = std::min(depth, info.depth);
  masks.masks.reserve(n);
  for (int d = 1; d <= n; ++d) {
    Result<std::vector<uint8_t>> level = impl_->decode_level(index, d);
    if (!level) return level.error();
    masks.masks.push_back(std::move(level).value());
  }
  return ObjectTree(info, std::move(masks));
}

Result<std::vector<uint8_t>> BakedFile::decode_level(size_t index, int level) const {
  if (index >= impl_->trees.size()) {
    return Error{ErrorCode::invalid_argument, impl_->label + ": no tree " + std::to_string(index)};
  }
  const TreeInfo& info = impl_->trees[index];
  if (level < 1 || level > info.depth) {
    return Error{ErrorCode::invalid_argument, tree_label(impl_->label, index, info.name) + ": no level " +
                                                  std::to_string(level) + " (levels 1.." +
                                                  std::to_string(info.depth) + ")"};
  }
  return impl_->decode_level(index, level);
}

// ---------------------------------------------------------------------------

Result<ModelLibrary> ModelLibrary::open(const std::string& source) {
  std::error_code ec;
  const auto status = std::filesystem::status(source, ec);
  if (!std::filesystem::exists(status)) {
    return Error{ErrorCode::not_found, source + ": no such folder or pack file"};
  }
  ModelLibrary library;
  library.source_ = source;
  library.is_pack_ = !std::filesystem::is_directory(status);
  if (library.is_pack_) {
    Result<BakedFile> pack = BakedFile::open(source);
    if (!pack) return pack.error();
    library.files_.emplace_back(source, std::move(pack).value());
  }
  return library;
}

Result<BakedFile*> ModelLibrary::file_for(const std::string& name, size_t* index) {
  const std::string folder = source_.ends_with('/') ? source_ : source_ + "/";
  const std::string missing = "no tree \"" + name + "\" in " + (is_pack_ ? source_ : folder);
  BakedFile* file = nullptr;
  if (is_pack_) {
    file = &files_.front().second;
  } else {
    const std::string path = folder + name + ".oct";
    for (auto& [p, f] : files_) {
      if (p == path) file = &f;
    }
    if (!file) {
      Result<BakedFile> opened = BakedFile::open(path);
      if (!opened) {
        if (opened.error().code == ErrorCode::not_found) return Error{ErrorCode::not_found, missing};
        return opened.error();
      }
      files_.emplace_back(path, std::move(opened).value());
      file = &files_.back().second;
    }
  }
  Result<size_t> found = file->find(name);
  if (found) {
    *index = *found;
  } else if (!is_pack_ && file->trees().size() == 1) {
    *index = 0;  // a renamed .oct still serves the model its file name says
  } else {
    return Error{ErrorCode::not_found, missing};
  }
  return file;
}

Result<ObjectTree> ModelLibrary::load(const std::string& name, int depth) {
  size_t index = 0;
  Result<BakedFile*> file = file_for(name, &index);
  if (!file) return file.error();
  return (*file)->load(index, depth);
}

Result<TreeInfo> ModelLibrary::info(const std::string& name) {
  size_t index = 0;
  Result<BakedFile*> file = file_for(name, &index);
  if (!file) return file.error();
  return (*file)->trees()[index];
}

LoadStats ModelLibrary::stats() const {
  LoadStats total;
  for (const auto& [path, file] : files_) {
    const LoadStats s = file.stats();
    total.files_opened += s.files_opened;
    total.bytes_mapped += s.bytes_mapped;
    total.levels_decoded += s.levels_decoded;
    total.bytes_decompressed += s.bytes_decompressed;
  }
  return total;
}

}  // namespace octbake
