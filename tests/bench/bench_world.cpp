// World::step per frame: N solid-box objects (trees of depth 3..6) on a
// jittered lattice of constant spacing, so density does not change with N; a
// third move at ~2 units/s, separate response, screen LOD, world cells about
// one spacing wide. Run: build with -DOCTBAKE_BENCH=ON, then
//   ./build/tests/bench_world --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "octbake/world.h"

namespace octbake {
namespace {

constexpr double kSpacing = 4.0;  // lattice pitch; objects are at most 1.8 wide

double unit(std::mt19937& rng) { return double(rng() >> 8) * (1.0 / 16777216.0); }

ObjectTree solid_box(const Eigen::Vector3d& half, int depth) {
  OctreeMasks m;
  m.bounds = {-half, half};
  for (int d = 0; d < depth; ++d) m.masks.emplace_back(size_t(1) << (3 * d), uint8_t{0xFF});
  TreeInfo info;
  info.bounds = m.bounds;
  info.depth = depth;
  return ObjectTree(std::move(info), std::move(m));
}

struct Scene {
  std::vector<ObjectTree> trees;
  WorldSettings settings;
  std::vector<ObjectDesc> objects;
};

// world_depth_offset: 0 gives cells about one spacing wide, -1 two spacings.
Scene make_scene(int n, int world_depth_offset = 0) {
  Scene s;
  s.trees = {solid_box({0.5, 0.5, 0.5}, 3), solid_box({0.9, 0.4, 0.6}, 4), solid_box({0.3, 0.8, 0.3}, 5),
             solid_box({0.7, 0.7, 0.7}, 6)};
  const int side = int(std::ceil(std::cbrt(double(n))));
  const double extent = side * kSpacing;
  s.settings.bounds = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(extent)};
  s.settings.world_depth = std::clamp(int(std::ceil(std::log2(side))) + world_depth_offset, 0, 10);
  s.settings.response = Response::separate;
  s.settings.lod.policy = LodPolicy::screen;
  s.settings.camera.position = {extent / 2, extent / 2, -extent};
  s.settings.camera.look_at = Eigen::Vector3d::Constant(extent / 2);
  std::mt19937 rng(42);
  for (int i = 0; i < n; ++i) {
    ObjectDesc o;
    o.tree = &s.trees[rng() % s.trees.size()];
    const Eigen::Vector3d cell(i % side, (i / side) % side, i / (side * side));
    const Eigen::Vector3d jitter(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
    o.pose.position = (cell.array() + 0.5).matrix() * kSpacing + jitter * 1.5;
    if (i % 3 == 0) {
      const Eigen::Vector3d dir(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
      o.velocity = dir.normalized() * 2.0;
    }
    s.objects.push_back(o);
  }
  return s;
}

void BM_WorldStep(benchmark::State& state) {
  Scene scene = make_scene(int(state.range(0)), int(state.range(1)));
  World world(scene.settings, scene.objects);
  std::vector<Collision> collisions;
  world.step(collisions);  // frame 0 computes every pixel area
  FrameStats total;
  uint64_t reinsertions = world.world_tree().reinsertions();
  for (auto _ : state) {
    collisions.clear();
    const FrameStats f = world.step(collisions);
    total.pair_tests += f.pair_tests;
    total.box_tests += f.box_tests;
    total.collisions += f.collisions;
    total.area_refreshes += f.area_refreshes;
  }
  reinsertions = world.world_tree().reinsertions() - reinsertions;
  const double frames = double(state.iterations());
  state.counters["pair_tests"] = double(total.pair_tests) / frames;
  state.counters["box_tests"] = double(total.box_tests) / frames;
  state.counters["collisions"] = double(total.collisions) / frames;
  state.counters["area_refreshes"] = double(total.area_refreshes) / frames;
  state.counters["reinsertions"] = double(reinsertions) / frames;
  state.counters["world_depth"] = scene.settings.world_depth;
}
BENCHMARK(BM_WorldStep)
    ->ArgsProduct({{210, 10'000, 100'000}, {0, -1}})
    ->ArgNames({"objects", "depth_offset"})
    ->Unit(benchmark::kMicrosecond);

// The broadphase alone, for the same scenes (no motion).
void BM_CandidatePairs(benchmark::State& state) {
  Scene scene = make_scene(int(state.range(0)));
  World world(scene.settings, scene.objects);
  std::vector<std::pair<uint32_t, uint32_t>> pairs;
  for (auto _ : state) {
    world.world_tree().candidate_pairs(pairs);
    benchmark::DoNotOptimize(pairs.data());
  }
  state.counters["pairs"] = double(pairs.size());
}
BENCHMARK(BM_CandidatePairs)->ArgName("objects")->Arg(210)->Arg(10'000)->Arg(100'000)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace octbake

BENCHMARK_MAIN();
