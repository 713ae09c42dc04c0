// CollisionWorld's parallel parts (set_poses, the WorldTree's cell checks,
// cell moves and pair scan, depths, pair tests) on 3 threads give the single-threaded
// results; under ThreadSanitizer (test.sh) this is where their data races
// would show.
#include <gtest/gtest.h>

#include <random>

#include "unit/runtime/collision_world_util.h"

namespace octbake {
namespace {

TEST(CollisionWorldThreads, ParallelDetectEqualsOneThread) {
  const uint64_t one = test::crowd_hash(4500, 6, 1, false);
  EXPECT_EQ(test::crowd_hash(4500, 6, 3, true), one);
  EXPECT_EQ(test::crowd_hash(4500, 6, 3, false), one);
  // set_poses batches refused before each frame's own.
  EXPECT_EQ(test::crowd_hash(4500, 6, 3, true, nullptr, LodPolicy::screen, AreaRefresh::on_demand, true), one);
}

// The passes over every object's area: thesis LOD (its global A_min, A_max)
// and the simulation layer's historic refresh modes.
TEST(CollisionWorldThreads, AreaPassesEqualOneThread) {
  for (const auto& [policy, refresh] : {std::pair{LodPolicy::thesis, AreaRefresh::on_demand},
                                        std::pair{LodPolicy::thesis, AreaRefresh::on_cell_change},
                                        std::pair{LodPolicy::screen, AreaRefresh::every_frame}}) {
    const uint64_t one = test::crowd_hash(4500, 4, 1, true, nullptr, policy, refresh);
    EXPECT_EQ(test::crowd_hash(4500, 4, 3, true, nullptr, policy, refresh), one)
        << to_string(policy) << ", refresh mode " << int(refresh);
  }
}

// The WorldTree's batch on a 3-thread pool, with enough objects changing
// cells per batch that every phase runs in parts, equals one-by-one updates.
TEST(WorldTreeThreads, BatchOnAPoolEqualsOneByOne) {
  ThreadPool pool(3);
  struct OnPool final : WorldTree::Parallel {
    ThreadPool* pool = nullptr;
    void for_ranges(size_t count, size_t grain, void (*task)(const void*, size_t, size_t), const void* ctx) override {
      pool->parallel_for(count, grain, RangeTask{task, ctx});
    }
  } on_pool;
  on_pool.pool = &pool;
  const Aabb world{{0, 0, 0}, {64, 64, 64}};
  WorldTree one(world, 5), batched(world, 5);  // cells 2 wide: boxes over at most 2x2x2
  std::mt19937 rng(3);
  const auto unit = [&] { return double(rng() >> 8) * (1.0 / 16777216.0); };
  const uint32_t n = 4000;
  std::vector<Eigen::Vector3d> at(n);
  std::vector<uint32_t> ids(n);
  std::vector<WorldTree::CellRange> ranges(n);
  std::vector<std::pair<uint32_t, uint32_t>> want, got;
  for (int frame = 0; frame < 8; ++frame) {
    for (uint32_t i = 0; i < n; ++i) {
      const Eigen::Vector3d r(unit(), unit(), unit());
      at[i] = frame == 0 ? Eigen::Vector3d(r * 64) : Eigen::Vector3d(at[i] + (r.array() - 0.5).matrix() * 3);
      const Aabb box{at[i].array() - 0.4, at[i].array() + 0.4};
      ids[i] = i;
      ranges[i] = one.cell_range(box);
      one.update(i, box);
    }
    batched.update_cells(ids, ranges, on_pool, 4);
    one.candidate_pairs(want);
    batched.candidate_pairs(got);
    ASSERT_EQ(got, want) << "frame " << frame;
    EXPECT_EQ(batched.reinsertions(), one.reinsertions());
  }
  EXPECT_GT(one.reinsertions(), 8000u);  // most objects changed cells in most frames
}

}  // namespace
}  // namespace octbake
