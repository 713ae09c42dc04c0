// Helpers for the baked-file tests: seeded random trees, an independent
// nesting check, and byte-level access to an encoded file.
#pragma once
#include <gtest/gtest.h>
#include <zstd.h>

#include <algorithm>
#include <bit>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <cstdint>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "octbake/baked_file.h"
#include "octbake/format.h"
#include "octbake_generated.h"

namespace octbake::test {

// [0, 1) from the raw generator output (no std distributions: they differ
// between standard libraries).
inline double unit(std::mt19937& rng) { return rng() / 4294967296.0; }
inline uint32_t below(std::mt19937& rng, uint32_t n) { return static_cast<uint32_t>(unit(rng) * n); }

// A random valid tree: each occupied box gets each child with probability
// `p`, at least one child except for about 1 box in 16 (empty masks are legal
// and worth covering). Levels are capped near `max_boxes` by thinning to one
// child per box.
inline OctreeMasks random_masks(std::mt19937& rng, int depth, double p = 0.3, uint64_t max_boxes = 4096) {
  OctreeMasks m;
  m.bounds.min = {-10 + 20 * unit(rng), -10 + 20 * unit(rng), -10 + 20 * unit(rng)};
  m.bounds.max = m.bounds.min + Eigen::Vector3d(20 * unit(rng), 20 * unit(rng), 20 * unit(rng));
  uint64_t parents = 1;
  for (int d = 0; d < depth; ++d) {
    const bool thin = parents * 8 * p > double(max_boxes);
    std::vector<uint8_t> level(parents);
    uint64_t children = 0;
    for (uint8_t& mask : level) {
      if (!thin) {
        for (int j = 0; j < 8; ++j) {
          if (unit(rng) < p) mask |= uint8_t(1u << j);
        }
      }
      if (mask == 0 && (thin || below(rng, 16) != 0)) mask = uint8_t(1u << below(rng, 8));
      children += std::popcount(mask);
    }
    m.masks.push_back(std::move(level));
    parents = children;
  }
  return m;
}

// A tree whose deepest level is 2 MiB of masks (every box above it full), in
// a few patterns: compressible like real masks, and several zstd jobs long;
// the seven levels above it are one job each (1 byte to 256 KiB).
inline TreeToEncode wide_tree() {
  constexpr int kDepth = 8;
  constexpr uint8_t kPatterns[] = {0x01, 0x03, 0x0f, 0x33, 0x55, 0xff};
  std::mt19937 g(8);
  TreeToEncode t;
  t.name = "wide";
  t.source_hash = "00";
  t.options.depth = kDepth;
  t.masks.bounds.max = {1, 2, 3};
  size_t boxes = 1;
  for (int d = 0; d < kDepth; ++d) {
    std::vector<uint8_t> level(boxes, 0xff);
    if (d + 1 == kDepth)
      for (uint8_t& m : level) m = kPatterns[g() % std::size(kPatterns)];
    t.masks.masks.push_back(std::move(level));
    boxes *= 8;
  }
  return t;
}

inline TreeToEncode random_tree(std::mt19937& rng, const std::string& name, int depth, Compression c) {
  TreeToEncode t;
  t.name = name;
  t.source_hash = "hash-of-" + name;
  t.options.depth = depth;
  t.options.occupancy = static_cast<Occupancy>(below(rng, 3));
  t.options.compression = c;
  t.options.compression_level = 1 + static_cast<int>(below(rng, 19));
  t.triangle_count = rng();
  t.vertex_count = rng();
  // Sparse masks barely compress; dense or thinned ones (like real meshes) do.
  t.masks = random_masks(rng, depth, below(rng, 2) ? 0.3 : 0.85);
  return t;
}

// Conservative nesting, checked from coordinates rather than from the
// decoder's bookkeeping: every level has one mask per box of the level above,
// and every box of depth d+1 lies inside an occupied box of depth d.
inline void expect_nesting(const ObjectTree& tree) {
  const OctreeMasks& m = tree.masks();
  ASSERT_EQ(tree.info().box_count.size(), size_t(tree.info().depth) + 1);
  for (int d = 0; d < m.depth(); ++d) {
    uint64_t boxes = 1;
    if (d > 0) {
      boxes = 0;
      for (uint8_t mask : m.masks[d - 1]) boxes += std::popcount(mask);
    }
    ASSERT_EQ(m.masks[d].size(), boxes) << "depth " << d;
    ASSERT_EQ(tree.info().box_count[d], boxes) << "depth " << d;
  }
  for (int d = 1; d <= m.depth(); ++d) {
    std::set<std::tuple<uint32_t, uint32_t, uint32_t>> parents;
    for (BoxCoord c : m.boxes(d - 1)) parents.insert({c.x, c.y, c.z});
    for (BoxCoord c : m.boxes(d)) {
      ASSERT_LT(std::max({c.x, c.y, c.z}), 1u << d);
      ASSERT_TRUE(parents.count({c.x / 2, c.y / 2, c.z / 2})) << "orphan box at depth " << d;
    }
  }
}

// The mutable root table of an encoded file (size-prefixed), for tests that
// forge or damage specific fields.
inline const fb::File& root_of(const std::vector<uint8_t>& bytes) { return *fb::GetSizePrefixedFile(bytes.data()); }

// Byte offset in `bytes` of scalar field `field` of `table` (which must be present).
template <class T>
size_t field_offset(const std::vector<uint8_t>& bytes, const T* table, flatbuffers::voffset_t field) {
  const auto* t = reinterpret_cast<const flatbuffers::Table*>(table);
  const uint8_t* p = t->GetAddressOf(field);
  EXPECT_NE(p, nullptr);
  return static_cast<size_t>(p - bytes.data());
}

template <class T>
void poke(std::vector<uint8_t>& bytes, size_t offset, T value) {
  std::memcpy(bytes.data() + offset, &value, sizeof(T));
}

// A fresh folder per test: ctest runs tests in parallel, so a fixture's folder
// name must include the running test's own name.
inline std::string temp_dir(const std::string& name) {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string dir = std::string(OCTBAKE_BINARY_DIR) + "/test_tmp/" + name;
  if (info) dir += std::string("_") + info->test_suite_name() + "." + info->name();
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline void write_file(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr) << path;
  if (!bytes.empty()) {
    ASSERT_EQ(std::fwrite(bytes.data(), 1, bytes.size(), f), bytes.size());
  }
  std::fclose(f);
}

inline std::vector<uint8_t> read_file(const std::string& path) {
  std::vector<uint8_t> bytes;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return bytes;
  uint8_t buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) bytes.insert(bytes.end(), buf, buf + n);
  std::fclose(f);
  return bytes;
}

// One zstd frame of `raw`, optionally without its content size.
inline std::vector<uint8_t> zstd_frame(const std::vector<uint8_t>& raw, bool content_size = true) {
  ZSTD_CCtx* cctx = ZSTD_createCCtx();
  ZSTD_CCtx_setParameter(cctx, ZSTD_c_contentSizeFlag, content_size ? 1 : 0);
  ZSTD_CCtx_setParameter(cctx, ZSTD_c_checksumFlag, 1);
  std::vector<uint8_t> frame(ZSTD_compressBound(raw.size()));
  const size_t n = ZSTD_compress2(cctx, frame.data(), frame.size(), raw.data(), raw.size());
  ZSTD_freeCCtx(cctx);
  EXPECT_FALSE(ZSTD_isError(n));
  frame.resize(n);
  return frame;
}

// Files whose every field the test chooses, so each header inconsistency can
// be written on purpose (encode_file only ever writes consistent ones).
struct ForgedLevel {
  uint64_t box_count = 0;
  uint64_t raw_size = 0;
  fb::Compression compression = fb::Compression::None;
  std::vector<uint8_t> data;
};

struct ForgedTree {
  std::string name = "forged";
  uint8_t depth = 0;
  uint8_t options_depth = 0;
  uint8_t occupancy = 0;
  uint8_t compression = 1;
  fb::Vec3 lo{0, 0, 0}, hi{1, 1, 1};
  std::vector<ForgedLevel> levels;
};

// A consistent forged tree for `m`, every level stored as `c`.
inline ForgedTree forged_from(const OctreeMasks& m, fb::Compression c) {
  ForgedTree t;
  t.depth = t.options_depth = static_cast<uint8_t>(m.depth());
  t.levels.push_back({1, 0, fb::Compression::None, {}});
  for (int d = 1; d <= m.depth(); ++d) {
    const std::vector<uint8_t>& raw = m.masks[d - 1];
    t.levels.push_back({m.box_count(d), raw.size(), c, c == fb::Compression::Zstd ? zstd_frame(raw) : raw});
  }
  return t;
}

inline std::vector<uint8_t> forge(const std::vector<ForgedTree>& trees, uint32_t version = kFormatVersion) {
  flatbuffers::FlatBufferBuilder fbb;
  fbb.ForceDefaults(true);
  std::vector<flatbuffers::Offset<fb::Tree>> offsets;
  for (const ForgedTree& t : trees) {
    std::vector<flatbuffers::Offset<fb::Level>> levels;
    for (const ForgedLevel& l : t.levels) {
      levels.push_back(fb::CreateLevel(fbb, l.box_count, l.raw_size, l.compression, fbb.CreateVector(l.data)));
    }
    const auto levels_offset = fbb.CreateVector(levels);
    const auto name = fbb.CreateString(t.name);
    const auto hash = fbb.CreateString("h");
    const auto options = fb::CreateBakeOptions(fbb, t.options_depth, static_cast<fb::Occupancy>(t.occupancy),
                                               static_cast<fb::Compression>(t.compression), 19);
    offsets.push_back(fb::CreateTree(fbb, name, hash, options, &t.lo, &t.hi, t.depth, 1, 1, levels_offset));
  }
  const auto trees_offset = fbb.CreateVector(offsets);
  const auto baker = fbb.CreateString("forge");
  fb::FinishSizePrefixedFileBuffer(fbb, fb::CreateFile(fbb, version, baker, trees_offset));
  return {fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize()};
}

// Every box of every depth occupied: box_count(d) = 8^d, all masks 0xFF.
inline OctreeMasks full_masks(int depth) {
  OctreeMasks m;
  m.bounds = {{0, 0, 0}, {1, 1, 1}};
  for (int d = 0; d < depth; ++d) m.masks.push_back(std::vector<uint8_t>(size_t(1) << (3 * d), 0xFF));
  return m;
}

}  // namespace octbake::test
