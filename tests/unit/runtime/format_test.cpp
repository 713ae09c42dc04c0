// encode_file round trips and determinism (schema/octbake.fbs).
#include <gtest/gtest.h>

#include "baked_test_util.h"

namespace octbake {
namespace {

using test::random_tree;

void expect_same_header(const TreeToEncode& in, const TreeInfo& out) {
  EXPECT_EQ(out.name, in.name);
  EXPECT_EQ(out.source_hash, in.source_hash);
  EXPECT_EQ(out.options, in.options);
  EXPECT_EQ(out.bounds, in.masks.bounds);
  EXPECT_EQ(out.depth, in.masks.depth());
  EXPECT_EQ(out.triangle_count, in.triangle_count);
  EXPECT_EQ(out.vertex_count, in.vertex_count);
  ASSERT_EQ(out.box_count.size(), size_t(in.masks.depth()) + 1);
  for (int d = 0; d <= in.masks.depth(); ++d) {
    EXPECT_EQ(out.box_count[d], in.masks.box_count(d)) << "depth " << d;
    EXPECT_EQ(out.raw_bytes[d], d == 0 ? 0 : in.masks.masks[d - 1].size()) << "depth " << d;
  }
}

class RoundTrip : public ::testing::TestWithParam<Compression> {};

TEST_P(RoundTrip, RandomTreesDecodeToTheSameMasks) {
  std::mt19937 rng(1234 + static_cast<int>(GetParam()));
  int zstd_levels = 0;
  for (int round = 0; round < 60; ++round) {
    const int depth = 1 + round % 8;
    const TreeToEncode tree = random_tree(rng, "t" + std::to_string(round), depth, GetParam());
    const std::vector<uint8_t> bytes = encode_file({&tree, 1}, "test-1.0");
    Result<BakedFile> file = BakedFile::from_bytes(bytes, "mem");
    ASSERT_TRUE(file.ok()) << file.error().message;
    EXPECT_EQ(file->format_version(), kFormatVersion);
    EXPECT_EQ(file->baker_version(), "test-1.0");
    ASSERT_EQ(file->trees().size(), 1u);
    expect_same_header(tree, file->trees()[0]);
    Result<ObjectTree> loaded = file->load(0, depth);
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    EXPECT_EQ(loaded->masks(), tree.masks);
    test::expect_nesting(*loaded);
    for (int d = 1; d <= depth; ++d) zstd_levels += file->trees()[0].stored_bytes[d] < file->trees()[0].raw_bytes[d];
  }
  // Random masks do compress at depth: the zstd path was really exercised.
  EXPECT_TRUE(GetParam() == Compression::none || zstd_levels > 20) << zstd_levels;
}

TEST_P(RoundTrip, PacksKeepEveryTreeAndFindByName) {
  std::mt19937 rng(99 + static_cast<int>(GetParam()));
  std::vector<TreeToEncode> trees;
  for (int i = 0; i < 7; ++i) trees.push_back(random_tree(rng, "model_" + std::to_string(i), 1 + i, GetParam()));
  const std::vector<uint8_t> bytes = encode_file(trees, "v");
  Result<BakedFile> file = BakedFile::from_bytes(bytes, "pack");
  ASSERT_TRUE(file.ok()) << file.error().message;
  ASSERT_EQ(file->trees().size(), trees.size());
  for (size_t i = 0; i < trees.size(); ++i) {
    Result<size_t> index = file->find(trees[i].name);
    ASSERT_TRUE(index.ok());
    EXPECT_EQ(*index, i);
    expect_same_header(trees[i], file->trees()[i]);
    Result<ObjectTree> loaded = file->load(i, 99);  // clamped to the baked depth
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    EXPECT_EQ(loaded->masks(), trees[i].masks);
  }
  Result<size_t> missing = file->find("nope");
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code, ErrorCode::not_found);
}

INSTANTIATE_TEST_SUITE_P(Compression, RoundTrip, ::testing::Values(Compression::none, Compression::zstd),
                         [](const auto& info) { return info.param == Compression::none ? "none" : "zstd"; });

TEST(Format, EncodingIsDeterministic) {
  std::mt19937 rng(7);
  std::vector<TreeToEncode> trees;
  for (int i = 0; i < 3; ++i) trees.push_back(random_tree(rng, "m" + std::to_string(i), 6, Compression::zstd));
  const std::vector<uint8_t> a = encode_file(trees, "v");
  const std::vector<uint8_t> b = encode_file(trees, "v");
  EXPECT_EQ(a, b);
  // A changed byte of content changes the file: the comparison is not vacuous.
  trees[1].masks.bounds.max.x() += 1;
  EXPECT_NE(encode_file(trees, "v"), a);
}

TEST(Format, SizePrefixAndIdentifierWhereTheSchemaSays) {
  std::mt19937 rng(3);
  const TreeToEncode tree = random_tree(rng, "x", 3, Compression::none);
  const std::vector<uint8_t> bytes = encode_file({&tree, 1}, "v");
  uint32_t prefix = 0;
  std::memcpy(&prefix, bytes.data(), 4);
  EXPECT_EQ(prefix + 4u, bytes.size());
  EXPECT_EQ(std::string(bytes.begin() + 8, bytes.begin() + 12), kFileIdentifier);
  EXPECT_EQ(bytes.size() % 8, 0u);  // whole file 8-aligned: doubles read in place
}

// Compressible levels are stored as zstd and smaller; levels that zstd cannot
// shrink stay raw, whatever the options ask for.
TEST(Format, ZstdOnlyWhereItShrinks) {
  TreeToEncode tree;
  tree.name = "solid";
  tree.options.depth = 4;
  tree.masks = test::full_masks(4);
  const std::vector<uint8_t> bytes = encode_file({&tree, 1}, "v");
  Result<BakedFile> file = BakedFile::from_bytes(bytes, "mem");
  ASSERT_TRUE(file.ok()) << file.error().message;
  const TreeInfo& info = file->trees()[0];
  EXPECT_EQ(info.stored_bytes[1], 1u);  // a 1-byte level cannot shrink
  EXPECT_EQ(info.raw_bytes[4], 512u);
  EXPECT_LT(info.stored_bytes[4], 64u);  // 512 x 0xFF is one short frame
  const auto& levels = *test::root_of(bytes).trees()->Get(0)->levels();
  EXPECT_EQ(levels.Get(1)->compression(), fb::Compression::None);
  EXPECT_EQ(levels.Get(4)->compression(), fb::Compression::Zstd);
  Result<ObjectTree> loaded = file->load(0, 4);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  EXPECT_EQ(loaded->masks(), tree.masks);
  EXPECT_EQ(loaded->box_count(4), 4096u);
}

TEST(Format, LoadingDepthZeroGivesTheRootOnly) {
  std::mt19937 rng(5);
  const TreeToEncode tree = random_tree(rng, "x", 5, Compression::zstd);
  const std::vector<uint8_t> bytes = encode_file({&tree, 1}, "v");
  Result<BakedFile> file = BakedFile::from_bytes(bytes, "mem");
  ASSERT_TRUE(file.ok());
  Result<ObjectTree> root = file->load(0, 0);
  ASSERT_TRUE(root.ok());
  EXPECT_EQ(root->loaded_depth(), 0);
  EXPECT_EQ(root->bounds(), tree.masks.bounds);
  EXPECT_EQ(file->load(1, 2).error().code, ErrorCode::invalid_argument);
  EXPECT_EQ(file->load(0, -1).error().code, ErrorCode::invalid_argument);
}

}  // namespace
}  // namespace octbake
