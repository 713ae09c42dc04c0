// load() decodes only what is asked for; ModelLibrary opens only what is named.
#include <gtest/gtest.h>

#include "baked_test_util.h"

namespace octbake {
namespace {

TEST(LazyLoad, OpeningDecodesNothingAndDepthTwoDecodesTwoLevels) {
  std::mt19937 rng(61);
  const TreeToEncode tree = test::random_tree(rng, "deep", 6, Compression::zstd);
  const std::string dir = test::temp_dir("lazy_depth");
  const std::vector<uint8_t> bytes = encode_file({&tree, 1}, "v");
  test::write_file(dir + "/deep.oct", bytes);

  Result<BakedFile> file = BakedFile::open(dir + "/deep.oct");
  ASSERT_TRUE(file.ok()) << file.error().message;
  EXPECT_EQ(file->stats().files_opened, 1u);
  EXPECT_EQ(file->stats().bytes_mapped, bytes.size());
  EXPECT_EQ(file->stats().levels_decoded, 0u);
  EXPECT_EQ(file->stats().bytes_decompressed, 0u);
  // The header is there without decoding: box counts of every level.
  for (int d = 0; d <= 6; ++d) EXPECT_EQ(file->trees()[0].box_count[d], tree.masks.box_count(d));

  Result<ObjectTree> shallow = file->load(0, 2);
  ASSERT_TRUE(shallow.ok()) << shallow.error().message;
  EXPECT_EQ(shallow->loaded_depth(), 2);
  EXPECT_EQ(file->stats().levels_decoded, 2u);
  EXPECT_EQ(file->stats().bytes_decompressed, tree.masks.masks[0].size() + tree.masks.masks[1].size());
  EXPECT_EQ(shallow->masks().masks[1], tree.masks.masks[1]);

  Result<ObjectTree> full = file->load(0, 6);
  ASSERT_TRUE(full.ok());
  uint64_t all = 0;
  for (const auto& level : tree.masks.masks) all += level.size();
  EXPECT_EQ(file->stats().levels_decoded, 2u + 6u);
  EXPECT_EQ(file->stats().bytes_decompressed, tree.masks.masks[0].size() + tree.masks.masks[1].size() + all);
}

// Level 4 is broken, yet depth 3 loads: deeper levels are never touched.
TEST(LazyLoad, LevelsBeyondTheAskedDepthAreNotRead) {
  test::ForgedTree t = test::forged_from(test::full_masks(5), fb::Compression::Zstd);
  t.levels[4].data.assign(t.levels[4].data.size(), 0x5A);
  const std::vector<uint8_t> bytes = test::forge({t});
  Result<BakedFile> file = BakedFile::from_bytes(bytes, "mem");
  ASSERT_TRUE(file.ok()) << file.error().message;
  EXPECT_TRUE(file->load(0, 3).ok());
  EXPECT_EQ(file->load(0, 4).error().code, ErrorCode::decompress_failed);
}

// decode_level(i, k) is level k alone, verified as load() verifies it.
TEST(LazyLoad, DecodeLevelIsOneLevelOfLoad) {
  std::mt19937 rng(62);
  std::vector<TreeToEncode> trees;
  for (Compression c : {Compression::zstd, Compression::none}) trees.push_back(test::random_tree(rng, "t" + std::to_string(trees.size()), 5, c));
  const std::vector<uint8_t> bytes = encode_file(trees, "v");
  Result<BakedFile> file = BakedFile::from_bytes(bytes, "mem");
  ASSERT_TRUE(file.ok()) << file.error().message;
  for (size_t t = 0; t < trees.size(); ++t) {
    for (int k = 5; k >= 1; --k) {  // any order: levels are independent
      Result<std::vector<uint8_t>> level = file->decode_level(t, k);
      ASSERT_TRUE(level.ok()) << level.error().message;
      EXPECT_EQ(*level, trees[t].masks.masks[k - 1]) << "tree " << t << " level " << k;
    }
  }
  EXPECT_EQ(file->stats().levels_decoded, 10u);
  for (int k : {0, 6, -1}) {
    Result<std::vector<uint8_t>> bad = file->decode_level(0, k);
    ASSERT_FALSE(bad.ok());
    EXPECT_EQ(bad.error().code, ErrorCode::invalid_argument);
    EXPECT_NE(bad.error().message.find("no level " + std::to_string(k)), std::string::npos) << bad.error().message;
  }
  EXPECT_EQ(file->decode_level(2, 1).error().code, ErrorCode::invalid_argument);
  EXPECT_EQ(file->stats().levels_decoded, 10u);

  // Damage is found the same way: broken level 4 of a forged file.
  test::ForgedTree f = test::forged_from(test::full_masks(5), fb::Compression::Zstd);
  f.levels[4].data.assign(f.levels[4].data.size(), 0x5A);
  const std::vector<uint8_t> forged = test::forge({f});
  Result<BakedFile> broken = BakedFile::from_bytes(forged, "forged");
  ASSERT_TRUE(broken.ok());
  EXPECT_TRUE(broken->decode_level(0, 5).ok());
  EXPECT_EQ(broken->decode_level(0, 4).error().code, ErrorCode::decompress_failed);
}

class Library : public ::testing::Test {
 protected:
  void SetUp() override {
    std::mt19937 rng(5);
    dir_ = test::temp_dir("library");
    for (int i = 0; i < 5; ++i) {
      trees_.push_back(test::random_tree(rng, "m" + std::to_string(i), 6, Compression::zstd));
      test::write_file(dir_ + "/m" + std::to_string(i) + ".oct", encode_file({&trees_.back(), 1}, "v"));
    }
  }
  std::string dir_;
  std::vector<TreeToEncode> trees_;
};

TEST_F(Library, FolderOpensOnlyTheFilesAskedFor) {
  Result<ModelLibrary> lib = ModelLibrary::open(dir_);
  ASSERT_TRUE(lib.ok()) << lib.error().message;
  EXPECT_EQ(lib->stats().files_opened, 0u);
  Result<ObjectTree> m1 = lib->load("m1", 3);
  ASSERT_TRUE(m1.ok()) << m1.error().message;
  EXPECT_EQ(m1->loaded_depth(), 3);
  EXPECT_EQ(m1->masks().masks[2], trees_[1].masks.masks[2]);
  EXPECT_EQ(lib->stats().files_opened, 1u);
  ASSERT_TRUE(lib->load("m3", 6).ok());
  ASSERT_TRUE(lib->load("m1", 6).ok());  // already open
  EXPECT_EQ(lib->stats().files_opened, 2u);
  EXPECT_EQ(lib->stats().levels_decoded, 3u + 6u + 6u);
  Result<TreeInfo> info = lib->info("m4");  // opens, decodes nothing
  ASSERT_TRUE(info.ok());
  EXPECT_EQ(info->box_count[6], trees_[4].masks.box_count(6));
  EXPECT_EQ(lib->stats().files_opened, 3u);
  EXPECT_EQ(lib->stats().levels_decoded, 15u);
}

TEST_F(Library, MissingModelNamesTheFolder) {
  Result<ModelLibrary> lib = ModelLibrary::open(dir_ + "/");
  ASSERT_TRUE(lib.ok());
  Result<ObjectTree> cat = lib->load("cat", 3);
  ASSERT_FALSE(cat.ok());
  EXPECT_EQ(cat.error().code, ErrorCode::not_found);
  EXPECT_EQ(cat.error().message, "no tree \"cat\" in " + dir_ + "/");
  Result<ModelLibrary> nowhere = ModelLibrary::open(dir_ + "/nowhere");
  ASSERT_FALSE(nowhere.ok());
  EXPECT_EQ(nowhere.error().code, ErrorCode::not_found);
}

TEST_F(Library, PackFindsTreesByName) {
  const std::string pack = dir_ + "/all.pack";
  test::write_file(pack, encode_file(trees_, "v"));
  Result<ModelLibrary> lib = ModelLibrary::open(pack);
  ASSERT_TRUE(lib.ok()) << lib.error().message;
  EXPECT_EQ(lib->stats().files_opened, 1u);
  for (int i : {4, 0, 2}) {
    Result<ObjectTree> t = lib->load("m" + std::to_string(i), 6);
    ASSERT_TRUE(t.ok()) << t.error().message;
    EXPECT_EQ(t->masks(), trees_[i].masks);
  }
  EXPECT_EQ(lib->stats().files_opened, 1u);
  EXPECT_EQ(lib->stats().levels_decoded, 18u);
  Result<ObjectTree> cat = lib->load("cat", 1);
  ASSERT_FALSE(cat.ok());
  EXPECT_EQ(cat.error().message, "no tree \"cat\" in " + pack);
}

// A broken model file is reported as broken, not as missing.
TEST_F(Library, BrokenFileKeepsItsErrorCode) {
  test::write_file(dir_ + "/bad.oct", {'n', 'o', 't', ' ', 'a', 'n', ' ', 'o', 'c', 't', 'b', 'a', 'k', 'e'});
  Result<ModelLibrary> lib = ModelLibrary::open(dir_);
  ASSERT_TRUE(lib.ok());
  Result<ObjectTree> bad = lib->load("bad", 1);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, ErrorCode::bad_identifier);
  EXPECT_NE(bad.error().message.find("bad.oct"), std::string::npos);
}

}  // namespace
}  // namespace octbake
