// encode_file on several threads: helper threads compress the one-job levels
// while the calling thread takes its share, then zstd's workers split the
// large level. Built and run under ThreadSanitizer by test.sh (ctest -L
// tsan); in every build it checks that each thread count writes the bytes
// one thread writes and that they decode to the masks given.
#include <gtest/gtest.h>

#include <random>

#include "octbake/baked_file.h"
#include "octbake/format.h"

namespace octbake {
namespace {

// Depth 8: seven full levels (one job each, 1 byte to 256 KiB) and a 2 MiB
// deepest level of mixed masks (several zstd jobs).
TreeToEncode tree_with_levels_of_every_kind() {
  constexpr int kDepth = 8;
  constexpr uint8_t kPatterns[] = {0x01, 0x03, 0x0f, 0x33, 0x55, 0xff};
  std::mt19937 rng(3);
  TreeToEncode t;
  t.name = "levels";
  t.source_hash = "00";
  t.options.depth = kDepth;
  t.options.compression_level = 3;  // quick under ThreadSanitizer; the paths are the same at 19
  t.masks.bounds.max = {1, 1, 1};
  size_t boxes = 1;
  for (int d = 0; d < kDepth; ++d) {
    std::vector<uint8_t> level(boxes, 0xff);
    if (d + 1 == kDepth)
      for (uint8_t& m : level) m = kPatterns[rng() % std::size(kPatterns)];
    t.masks.masks.push_back(std::move(level));
    boxes *= 8;
  }
  return t;
}

TEST(EncodeThreadsTsan, HelpersAndZstdWorkersWriteOneThreadsBytes) {
  const TreeToEncode tree = tree_with_levels_of_every_kind();
  ASSERT_GE(encode_threads_useful({&tree, 1}), 4);
  const std::vector<uint8_t> one = encode_file({&tree, 1}, "v", 1);
  for (int threads : {2, 4}) EXPECT_EQ(encode_file({&tree, 1}, "v", threads), one) << threads << " threads";
  auto file = BakedFile::from_bytes(one, "mem");
  ASSERT_TRUE(file.ok()) << file.error().message;
  auto loaded = file->load(0, tree.options.depth);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  EXPECT_EQ(loaded->masks(), tree.masks);
}

}  // namespace
}  // namespace octbake
