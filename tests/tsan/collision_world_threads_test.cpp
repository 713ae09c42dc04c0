// CollisionWorld's parallel parts (set_poses, the WorldTree's cell checks and
// pair scan, depths, pair tests) on 3 threads give the single-threaded
// results; under ThreadSanitizer (test.sh) this is where their data races
// would show.
#include <gtest/gtest.h>

#include "unit/runtime/collision_world_util.h"

namespace octbake {
namespace {

TEST(CollisionWorldThreads, ParallelDetectEqualsOneThread) {
  const uint64_t one = test::crowd_hash(1500, 6, 1, false);
  EXPECT_EQ(test::crowd_hash(1500, 6, 3, true), one);
  EXPECT_EQ(test::crowd_hash(1500, 6, 3, false), one);
}

}  // namespace
}  // namespace octbake
