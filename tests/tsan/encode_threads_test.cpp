// encode_file on several threads: helper threads compress the one-job levels
// while the calling thread takes its share, then zstd's workers split the
// large level. Built and run under ThreadSanitizer by test.sh (ctest -L
// tsan); in every build it checks that each thread count writes the bytes
// one thread writes and that they decode to the masks given.
#include <gtest/gtest.h>

#include "octbake/baked_file.h"
#include "octbake/format.h"
#include "unit/runtime/baked_test_util.h"

namespace octbake {
namespace {

TEST(EncodeThreadsTsan, HelpersAndZstdWorkersWriteOneThreadsBytes) {
  TreeToEncode tree = test::wide_tree();
  tree.options.compression_level = 3;  // quick under ThreadSanitizer; the paths are the same at 19
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
