// Every class of damaged file gets its own error code and never a crash.
// Run under ASan+UBSan too (OCTBAKE_SANITIZE=ON).
#include <gtest/gtest.h>

#include <cmath>

#include "baked_test_util.h"

namespace octbake {
namespace {

using test::forge;
using test::forged_from;
using test::full_masks;

ErrorCode open_error(const std::vector<uint8_t>& bytes) {
  Result<BakedFile> file = BakedFile::from_bytes(bytes, "bad.oct");
  EXPECT_FALSE(file.ok());
  if (file.ok()) return ErrorCode::invalid_argument;
  EXPECT_NE(file.error().message.find("bad.oct"), std::string::npos) << file.error().message;
  return file.error().code;
}

// Opens fine, then load() of tree 0 at full depth fails; returns that error.
Error load_error(const std::vector<uint8_t>& bytes) {
  Result<BakedFile> file = BakedFile::from_bytes(bytes, "bad.oct");
  EXPECT_TRUE(file.ok()) << file.error().message;
  if (!file.ok()) return file.error();
  Result<ObjectTree> tree = file->load(0, file->trees()[0].depth);
  EXPECT_FALSE(tree.ok());
  return tree.ok() ? Error{ErrorCode::invalid_argument, "loaded"} : tree.error();
}

std::vector<uint8_t> small_file(Compression c) {
  std::mt19937 rng(11);
  TreeToEncode tree = test::random_tree(rng, "small", 3, c);
  tree.masks = full_masks(3);  // 64-byte level 3: compressible, so zstd is used
  return encode_file({&tree, 1}, "v");
}

TEST(Corruption, TruncationAtEveryByteIsTruncated) {
  for (Compression c : {Compression::none, Compression::zstd}) {
    const std::vector<uint8_t> bytes = small_file(c);
    for (size_t n = 0; n < bytes.size(); ++n) {
      Result<BakedFile> file = BakedFile::from_bytes({bytes.data(), n}, "cut.oct");
      ASSERT_FALSE(file.ok()) << n;
      ASSERT_EQ(file.error().code, ErrorCode::truncated) << n << ": " << file.error().message;
    }
  }
}

TEST(Corruption, TrailingBytesAreCorrupt) {
  std::vector<uint8_t> bytes = small_file(Compression::zstd);
  bytes.push_back(0);
  EXPECT_EQ(open_error(bytes), ErrorCode::corrupt);
}

TEST(Corruption, WrongIdentifier) {
  std::vector<uint8_t> bytes = small_file(Compression::none);
  bytes[11] = 'X';
  EXPECT_EQ(open_error(bytes), ErrorCode::bad_identifier);
  const std::string text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";  // someone's OBJ
  EXPECT_EQ(open_error({text.begin(), text.end()}), ErrorCode::bad_identifier);
}

TEST(Corruption, NewerVersionNamesBothVersions) {
  std::vector<uint8_t> bytes = small_file(Compression::zstd);
  const size_t at = test::field_offset(bytes, &test::root_of(bytes), fb::File::VT_FORMAT_VERSION);
  test::poke<uint32_t>(bytes, at, 3);
  Result<BakedFile> file = BakedFile::from_bytes(bytes, "future.oct");
  ASSERT_FALSE(file.ok());
  EXPECT_EQ(file.error().code, ErrorCode::unsupported_version);
  EXPECT_EQ(file.error().message, "future.oct: format version 3, this build reads up to 1; rebake");
  // A newer version is refused as such even if its layout is past our verifier.
  test::ForgedTree nonsense = forged_from(full_masks(2), fb::Compression::None);
  nonsense.depth = 0;
  const std::vector<uint8_t> newer = forge({nonsense}, /*version=*/kFormatVersion + 1);
  EXPECT_EQ(open_error(newer), ErrorCode::unsupported_version);
  test::poke<uint32_t>(bytes, at, 0);
  EXPECT_EQ(open_error(bytes), ErrorCode::corrupt);
}

TEST(Corruption, RandomByteFlipsFailCleanlyOrStillNest) {
  std::mt19937 rng(2024);
  std::vector<TreeToEncode> trees;
  trees.push_back(test::random_tree(rng, "a", 5, Compression::zstd));
  trees.push_back(test::random_tree(rng, "b", 3, Compression::none));
  trees.back().masks = full_masks(3);  // a raw level big enough to be hit often
  trees.back().options.compression = Compression::none;
  const std::vector<uint8_t> clean = encode_file(trees, "v");
  int loaded = 0, refused = 0;
  std::set<ErrorCode> codes;
  for (int trial = 0; trial < 3000; ++trial) {
    std::vector<uint8_t> bytes = clean;
    const int flips = 1 + static_cast<int>(test::below(rng, 3));
    for (int k = 0; k < flips; ++k) {
      bytes[test::below(rng, uint32_t(bytes.size()))] ^= uint8_t(1 + test::below(rng, 255));
    }
    Result<BakedFile> file = BakedFile::from_bytes(bytes, "flipped.oct");
    if (!file.ok()) {
      ++refused;
      codes.insert(file.error().code);
      continue;
    }
    for (size_t i = 0; i < file->trees().size(); ++i) {
      Result<ObjectTree> tree = file->load(i, kMaxDepth);
      if (!tree.ok()) {
        ++refused;
        codes.insert(tree.error().code);
        continue;
      }
      ++loaded;
      test::expect_nesting(*tree);
      if (::testing::Test::HasFatalFailure()) return;
    }
  }
  // Both outcomes happen, so neither branch is vacuous.
  EXPECT_GT(loaded, 300);
  EXPECT_GT(refused, 300);
  EXPECT_TRUE(codes.count(ErrorCode::corrupt));
  EXPECT_TRUE(codes.count(ErrorCode::decompress_failed));
}

TEST(Corruption, VerifierRejectsOffsetsOutsideTheFile) {
  std::vector<uint8_t> bytes = small_file(Compression::none);
  const fb::File& root = test::root_of(bytes);
  const size_t at = test::field_offset(bytes, &root, fb::File::VT_TREES);
  test::poke<uint32_t>(bytes, at, 0x7ffffff0u);
  EXPECT_EQ(open_error(bytes), ErrorCode::corrupt);
}

// A frame whose content size differs from the header's raw size.
TEST(Corruption, ZstdFrameLyingAboutItsSize) {
  test::ForgedTree t = forged_from(full_masks(4), fb::Compression::Zstd);
  t.levels[3].data = test::zstd_frame(std::vector<uint8_t>(70, 0xFF));  // header: 64
  const Error e = load_error(forge({t}));
  EXPECT_EQ(e.code, ErrorCode::decompress_failed);
  EXPECT_NE(e.message.find("level 3: frame says 70 bytes, header says 64"), std::string::npos) << e.message;
}

TEST(Corruption, ZstdFramesThatAreNotExactlyOneSizedFrame) {
  const OctreeMasks m = full_masks(4);
  std::vector<std::vector<uint8_t>> bad_frames;
  bad_frames.push_back(test::zstd_frame(m.masks[3], /*content_size=*/false));
  std::vector<uint8_t> two = test::zstd_frame(m.masks[3]);
  const std::vector<uint8_t> empty_frame = test::zstd_frame({});
  two.insert(two.end(), empty_frame.begin(), empty_frame.end());
  bad_frames.push_back(two);
  std::vector<uint8_t> garbage(40, 0x5A);
  bad_frames.push_back(garbage);
  std::vector<uint8_t> bad_checksum = test::zstd_frame(m.masks[3]);
  bad_checksum.back() ^= 1;  // the last 4 bytes are the checksum
  bad_frames.push_back(bad_checksum);
  for (const auto& frame : bad_frames) {
    test::ForgedTree t = forged_from(m, fb::Compression::Zstd);
    t.levels[4].data = frame;
    EXPECT_EQ(load_error(forge({t})).code, ErrorCode::decompress_failed);
  }
}

TEST(Corruption, RawLevelShorterThanItsHeader) {
  test::ForgedTree t = forged_from(full_masks(3), fb::Compression::None);
  t.levels[3].data.resize(60);
  EXPECT_EQ(open_error(forge({t})), ErrorCode::corrupt);
}

TEST(Corruption, BoxCountDisagreeingWithTheMasks) {
  for (fb::Compression c : {fb::Compression::None, fb::Compression::Zstd}) {
    test::ForgedTree t = forged_from(full_masks(3), c);
    t.levels[3].box_count = 511;  // the masks hold 512
    const Error e = load_error(forge({t}));
    EXPECT_EQ(e.code, ErrorCode::corrupt);
    EXPECT_NE(e.message.find("masks hold 512 boxes, header says 511"), std::string::npos) << e.message;
  }
}

TEST(Corruption, HeaderInconsistenciesAreCorruptAtOpen) {
  using Edit = void (*)(test::ForgedTree&);
  const std::vector<std::pair<const char*, Edit>> edits = {
      {"raw size != boxes above", [](test::ForgedTree& t) { t.levels[2].raw_size = 9; }},
      {"more than 8 children per box", [](test::ForgedTree& t) { t.levels[2].box_count = 65; }},
      {"root level with two boxes", [](test::ForgedTree& t) { t.levels[0].box_count = 2; }},
      {"root level with data", [](test::ForgedTree& t) { t.levels[0].data = {1}; }},
      {"depth 0", [](test::ForgedTree& t) { t.depth = t.options_depth = 0; t.levels.resize(1); }},
      {"depth 13", [](test::ForgedTree& t) { t.depth = t.options_depth = 13; }},
      {"missing level", [](test::ForgedTree& t) { t.levels.pop_back(); }},
      {"options depth differs", [](test::ForgedTree& t) { t.options_depth = 2; }},
      {"NaN bounds", [](test::ForgedTree& t) { t.lo = fb::Vec3(std::nan(""), 0, 0); }},
      {"infinite bounds", [](test::ForgedTree& t) { t.hi = fb::Vec3(1, HUGE_VAL, 1); }},
      {"min above max", [](test::ForgedTree& t) { t.lo = fb::Vec3(0, 2, 0); }},
      {"unknown level compression", [](test::ForgedTree& t) { t.levels[1].compression = fb::Compression(7); }},
      {"unknown option compression", [](test::ForgedTree& t) { t.compression = 9; }},
      {"unknown occupancy", [](test::ForgedTree& t) { t.occupancy = 3; }},
      {"empty name", [](test::ForgedTree& t) { t.name.clear(); }},
  };
  // The unedited forgery opens: each edit alone is what gets refused.
  ASSERT_TRUE(BakedFile::from_bytes(forge({forged_from(full_masks(3), fb::Compression::None)}), "ok").ok());
  for (const auto& [what, edit] : edits) {
    test::ForgedTree t = forged_from(full_masks(3), fb::Compression::None);
    edit(t);
    const std::vector<uint8_t> bytes = forge({t});
    EXPECT_EQ(open_error(bytes), ErrorCode::corrupt) << what;
  }
}

TEST(Corruption, DuplicateNamesInAPack) {
  const test::ForgedTree t = forged_from(full_masks(2), fb::Compression::None);
  const Result<BakedFile> file = BakedFile::from_bytes(forge({t, t}), "pack.oct");
  ASSERT_FALSE(file.ok());
  EXPECT_EQ(file.error().code, ErrorCode::corrupt);
  EXPECT_NE(file.error().message.find("two trees named \"forged\""), std::string::npos) << file.error().message;
}

// A tiny frame cannot decode to megabytes; such a claim is refused before
// anything is allocated.
TEST(Corruption, DecompressionBombRefusedAtOpen) {
  test::ForgedTree t;
  t.depth = t.options_depth = 8;
  t.levels.push_back({1, 0, fb::Compression::None, {}});
  uint64_t boxes = 1;
  for (int d = 1; d <= 8; ++d) {
    t.levels.push_back({boxes * 8, boxes, fb::Compression::Zstd, std::vector<uint8_t>(d < 8 ? 64 : 16, 0)});
    boxes *= 8;
  }
  EXPECT_EQ(open_error(forge({t})), ErrorCode::corrupt);
  t.levels[8].data.resize(64);  // now within zstd's maximum ratio: opens, fails to decode
  EXPECT_EQ(load_error(forge({t})).code, ErrorCode::decompress_failed);
}

}  // namespace
}  // namespace octbake
