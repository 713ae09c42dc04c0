// Cost of one pair test (collide) per depth pair, for spider vs duck (assimp's
// sample models) at four poses: overlapping / only roots overlapping, each
// axis-aligned and rotated. Counters: box tests per call and whether it hit.
//   cmake -B build-bench -DCMAKE_BUILD_TYPE=Release -DOCTBAKE_BENCH=ON
//   cmake --build build-bench --target bench_pair
//   build-bench/tests/bench_pair --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>

#include "build_tree.h"
#include "import.h"
#include "octbake/collide.h"

namespace octbake {
namespace {

constexpr int kDepth = 6;

struct Model {
  ObjectTree tree;
  double radius = 1;
  Eigen::Vector3d centre;
};

Model load(const char* path) {
  Result<Mesh> mesh = import_mesh(path);
  if (!mesh) {
    std::fprintf(stderr, "bench_pair: %s: %s\n", path, mesh.error().message.c_str());
    std::exit(1);
  }
  OctreeMasks masks = build_tree(*mesh, kDepth, Occupancy::surface);
  Model m;
  m.centre = 0.5 * (masks.bounds.min + masks.bounds.max);
  m.radius = 0.5 * (masks.bounds.max - masks.bounds.min).norm();
  TreeInfo info;
  info.bounds = masks.bounds;
  info.depth = kDepth;
  m.tree = ObjectTree(std::move(info), std::move(masks));
  return m;
}

const Model& spider() {
  static const Model m = load("/usr/share/assimp/models/OBJ/spider.obj");
  return m;
}
const Model& duck() {
  static const Model m = load("/usr/share/assimp/models/Collada/duck.dae");
  return m;
}

// Both normalised to radius 1, B's centre at `offset` from A's.
std::pair<Pose, Pose> poses(const Eigen::Vector3d& offset, bool rotated) {
  Pose a, b;
  if (rotated) {
    a.rotation = Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, 2, 3).normalized());
    b.rotation = Eigen::AngleAxisd(2.1, Eigen::Vector3d(-2, 1, 0.5).normalized());
  }
  a.scale = 1 / spider().radius;
  b.scale = 1 / duck().radius;
  a.position = -(a.rotation * (a.scale * spider().centre));
  b.position = offset - b.rotation * (b.scale * duck().centre);
  return {a, b};
}

// The nearest offset along a diagonal where the roots overlap but 6-6 does not.
Eigen::Vector3d roots_only_offset(bool rotated) {
  const Eigen::Vector3d dir = Eigen::Vector3d(1, 0.7, 0.4).normalized();
  for (double d = 0; d < 4; d += 0.01) {
    const auto [a, b] = poses(d * dir, rotated);
    if (collide({&spider().tree, a, 0}, {&duck().tree, b, 0}).hit &&
        !collide({&spider().tree, a, kDepth}, {&duck().tree, b, kDepth}).hit)
      return d * dir;
  }
  std::fprintf(stderr, "bench_pair: no roots-only pose\n");
  std::exit(1);
}

// args: depth a, depth b, pose (0 overlap, 1 overlap rotated, 2 roots only, 3 roots only rotated)
void BM_Collide(benchmark::State& state) {
  const int da = int(state.range(0)), db = int(state.range(1)), kind = int(state.range(2));
  const bool rotated = kind % 2 == 1;
  const Eigen::Vector3d offset = kind < 2 ? Eigen::Vector3d(0.3, 0.1, 0) : roots_only_offset(rotated);
  const auto [pa, pb] = poses(offset, rotated);
  const PlacedTree a{&spider().tree, pa, da}, b{&duck().tree, pb, db};
  PairTest r;
  for (auto _ : state) {
    r = collide(a, b);
    benchmark::DoNotOptimize(r);
  }
  state.counters["box_tests"] = double(r.box_tests);
  state.counters["hit"] = r.hit;
  state.counters["ns_per_box_test"] =
      benchmark::Counter(double(r.box_tests) * double(state.iterations()),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  static const char* kNames[] = {"overlap", "overlap_rotated", "roots_only", "roots_only_rotated"};
  state.SetLabel(kNames[kind]);
}

void depth_pairs(benchmark::internal::Benchmark* b) {
  for (int kind = 0; kind < 4; ++kind)
    for (int da = 1; da <= kDepth; ++da)
      for (int db = da; db <= kDepth; ++db) b->Args({da, db, kind});
}
// Best of N (run with --benchmark_repetitions=N): the least disturbed run.
BENCHMARK(BM_Collide)->Apply(depth_pairs)->ComputeStatistics("min", [](const std::vector<double>& v) {
  return *std::min_element(v.begin(), v.end());
});

}  // namespace
}  // namespace octbake

BENCHMARK_MAIN();
