// BakedFile on disk (mmap) and the committed golden files of every format
// version (tests/golden/README.md says how they were made).
#include <gtest/gtest.h>

#include <cstdlib>

#include "baked_test_util.h"

namespace octbake {
namespace {

const std::string kGolden = std::string(OCTBAKE_SOURCE_DIR) + "/tests/golden/";

TEST(BakedFile, MissingEmptyAndNonFiles) {
  const std::string dir = test::temp_dir("open_errors");
  Result<BakedFile> missing = BakedFile::open(dir + "/none.oct");
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code, ErrorCode::not_found);
  EXPECT_NE(missing.error().message.find("none.oct"), std::string::npos);

  test::write_file(dir + "/empty.oct", {});
  Result<BakedFile> empty = BakedFile::open(dir + "/empty.oct");
  ASSERT_FALSE(empty.ok());
  EXPECT_EQ(empty.error().code, ErrorCode::truncated);

  Result<BakedFile> folder = BakedFile::open(dir);
  ASSERT_FALSE(folder.ok());
  EXPECT_EQ(folder.error().code, ErrorCode::io_error);
}

TEST(BakedFile, MappedFileMatchesBytesAndOutlivesMoves) {
  std::mt19937 rng(8);
  std::vector<TreeToEncode> trees;
  for (int i = 0; i < 3; ++i) trees.push_back(test::random_tree(rng, "p" + std::to_string(i), 5, Compression::zstd));
  const std::string dir = test::temp_dir("mapped");
  test::write_file(dir + "/pack.oct", encode_file(trees, "baker 9"));
  Result<BakedFile> opened = BakedFile::open(dir + "/pack.oct");
  ASSERT_TRUE(opened.ok()) << opened.error().message;
  BakedFile file = std::move(opened).value();  // the mapping moves with it
  EXPECT_EQ(file.path(), dir + "/pack.oct");
  EXPECT_EQ(file.baker_version(), "baker 9");
  for (size_t i = 0; i < trees.size(); ++i) {
    Result<ObjectTree> t = file.load(i, 5);
    ASSERT_TRUE(t.ok()) << t.error().message;
    EXPECT_EQ(t->masks(), trees[i].masks);
    EXPECT_EQ(t->info().name, trees[i].name);
  }
}

TEST(BakedFile, MisalignedBytesAreCopiedNotMisread) {
  std::mt19937 rng(9);
  const TreeToEncode tree = test::random_tree(rng, "x", 4, Compression::zstd);
  const std::vector<uint8_t> bytes = encode_file({&tree, 1}, "v");
  std::vector<uint8_t> shifted(bytes.size() + 1);
  std::memcpy(shifted.data() + 1, bytes.data(), bytes.size());
  Result<BakedFile> file = BakedFile::from_bytes({shifted.data() + 1, bytes.size()}, "shifted");
  ASSERT_TRUE(file.ok()) << file.error().message;
  EXPECT_EQ(file->trees()[0].bounds, tree.masks.bounds);
  Result<ObjectTree> t = file->load(0, 4);
  ASSERT_TRUE(t.ok());
  EXPECT_EQ(t->masks(), tree.masks);
}

// --- golden files ----------------------------------------------------------

// Two opposite corners: octants 0 and 7 at depth 1, then the outermost child
// of each, so depth 2 holds boxes (0,0,0) and (3,3,3).
TreeToEncode golden_corners() {
  TreeToEncode t;
  t.name = "corners";
  t.source_hash = "0123456789abcdef";
  t.options = {/*depth=*/2, Occupancy::vertices, Compression::none, /*compression_level=*/0};
  t.triangle_count = 12;
  t.vertex_count = 8;
  t.masks.bounds = {{-1, -2, -3}, {1, 2, 3}};
  t.masks.masks = {{0x81}, {0x01, 0x80}};
  return t;
}

// A full cube of depth 3, zstd:19: level 3 (64 x 0xFF) is stored as a frame.
TreeToEncode golden_solid() {
  TreeToEncode t;
  t.name = "solid";
  t.source_hash = "fedcba9876543210";
  t.options = {/*depth=*/3, Occupancy::solid, Compression::zstd, /*compression_level=*/19};
  t.triangle_count = 12;
  t.vertex_count = 8;
  t.masks = test::full_masks(3);
  t.masks.bounds = {{0, 0, 0}, {4, 2, 1}};
  return t;
}

std::vector<uint8_t> golden_bytes(const std::string& name) {
  std::vector<uint8_t> bytes = test::read_file(kGolden + name);
  EXPECT_FALSE(bytes.empty()) << "missing golden file " << name;
  return bytes;
}

// Writes the golden files of the current format version. Run only by hand:
//   OCTBAKE_WRITE_GOLDEN=1 ./test_runtime --gtest_filter=Golden.Write
TEST(Golden, Write) {
  if (!std::getenv("OCTBAKE_WRITE_GOLDEN")) GTEST_SKIP() << "set OCTBAKE_WRITE_GOLDEN=1 to rewrite tests/golden";
  const std::string v = "v" + std::to_string(kFormatVersion) + "_";
  const TreeToEncode corners = golden_corners(), solid = golden_solid();
  const std::vector<uint8_t> corners_bytes = encode_file({&corners, 1}, "golden");
  test::write_file(kGolden + v + "corners_none.oct", corners_bytes);
  test::write_file(kGolden + v + "solid_zstd.oct", encode_file({&solid, 1}, "golden"));
  const std::vector<TreeToEncode> both = {corners, solid};
  test::write_file(kGolden + v + "pack.oct", encode_file(both, "golden"));

  std::vector<uint8_t> bad = corners_bytes;
  bad[11] = 'X';  // identifier "OCTX"
  test::write_file(kGolden + "golden_bad_identifier.oct", bad);
  bad = corners_bytes;
  const size_t at = test::field_offset(bad, &test::root_of(bad), fb::File::VT_FORMAT_VERSION);
  test::poke<uint32_t>(bad, at, kFormatVersion + 1);
  test::write_file(kGolden + "golden_future_version.oct", bad);
  bad.assign(corners_bytes.begin(), corners_bytes.begin() + corners_bytes.size() / 2);
  test::write_file(kGolden + "golden_truncated.oct", bad);
  test::ForgedTree lying = test::forged_from(solid.masks, fb::Compression::Zstd);
  lying.levels[3].data = test::zstd_frame(std::vector<uint8_t>(65, 0xFF));  // header says 64
  test::write_file(kGolden + "golden_lying_frame.oct", test::forge({lying}));
}

void expect_corners(const BakedFile& file, size_t index) {
  const TreeInfo& info = file.trees()[index];
  EXPECT_EQ(info.name, "corners");
  EXPECT_EQ(info.source_hash, "0123456789abcdef");
  EXPECT_EQ(info.options.occupancy, Occupancy::vertices);
  EXPECT_EQ(info.bounds, (Aabb{{-1, -2, -3}, {1, 2, 3}}));
  EXPECT_EQ(info.box_count, (std::vector<uint64_t>{1, 2, 2}));
  EXPECT_EQ(info.triangle_count, 12u);
  Result<ObjectTree> t = file.load(index, 2);
  ASSERT_TRUE(t.ok()) << t.error().message;
  EXPECT_EQ(t->masks().boxes(1), (std::vector<BoxCoord>{{0, 0, 0}, {1, 1, 1}}));
  EXPECT_EQ(t->masks().boxes(2), (std::vector<BoxCoord>{{0, 0, 0}, {3, 3, 3}}));
}

void expect_solid(const BakedFile& file, size_t index) {
  const TreeInfo& info = file.trees()[index];
  EXPECT_EQ(info.name, "solid");
  EXPECT_EQ(info.options.compression_level, 19);
  EXPECT_EQ(info.box_count, (std::vector<uint64_t>{1, 8, 64, 512}));
  EXPECT_LT(info.stored_bytes[3], info.raw_bytes[3]);  // really a zstd frame
  Result<ObjectTree> t = file.load(index, 3);
  ASSERT_TRUE(t.ok()) << t.error().message;
  const std::vector<BoxCoord> boxes = t->masks().boxes(3);
  ASSERT_EQ(boxes.size(), 512u);
  std::set<std::tuple<uint32_t, uint32_t, uint32_t>> distinct;
  for (BoxCoord c : boxes) distinct.insert({c.x, c.y, c.z});
  EXPECT_EQ(distinct.size(), 512u);  // every box of the 8x8x8 grid
  EXPECT_EQ(t->masks().box_bounds(3, {7, 7, 7}), (Aabb{{3.5, 1.75, 0.875}, {4, 2, 1}}));
}

TEST(Golden, Version1FilesLoad) {
  const std::vector<uint8_t> corners = golden_bytes("v1_corners_none.oct");
  const std::vector<uint8_t> solid = golden_bytes("v1_solid_zstd.oct");
  const std::vector<uint8_t> pack = golden_bytes("v1_pack.oct");
  for (const auto* bytes : {&corners, &solid, &pack}) {
    Result<BakedFile> file = BakedFile::from_bytes(*bytes, "golden");
    ASSERT_TRUE(file.ok()) << file.error().message;
    EXPECT_EQ(file->format_version(), 1u);
    EXPECT_EQ(file->baker_version(), "golden");
    if (bytes != &solid) expect_corners(*file, 0);
    if (bytes != &corners) expect_solid(*file, bytes == &pack ? 1 : 0);
  }
  // Raw levels do not depend on the zstd version: today's encoder must still
  // write the committed bytes.
  const TreeToEncode spec = golden_corners();
  EXPECT_EQ(encode_file({&spec, 1}, "golden"), corners);
}

TEST(Golden, MustRejectFilesAreRejected) {
  const std::vector<std::pair<const char*, ErrorCode>> cases = {
      {"golden_bad_identifier.oct", ErrorCode::bad_identifier},
      {"golden_future_version.oct", ErrorCode::unsupported_version},
      {"golden_truncated.oct", ErrorCode::truncated},
  };
  for (const auto& [name, code] : cases) {
    Result<BakedFile> file = BakedFile::open(kGolden + name);
    ASSERT_FALSE(file.ok()) << name;
    EXPECT_EQ(file.error().code, code) << name << ": " << file.error().message;
  }
  Result<BakedFile> lying = BakedFile::open(kGolden + "golden_lying_frame.oct");
  ASSERT_TRUE(lying.ok()) << lying.error().message;  // its header is consistent
  Result<ObjectTree> t = lying->load(0, 3);
  ASSERT_FALSE(t.ok());
  EXPECT_EQ(t.error().code, ErrorCode::decompress_failed);
  EXPECT_TRUE(lying->load(0, 2).ok());
}

}  // namespace
}  // namespace octbake
