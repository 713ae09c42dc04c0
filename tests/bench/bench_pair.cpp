// Cost of one pair test, the new descent (collide) against the scalar
// reference it replaced (collide_reference), measured in the same run.
//   BM_Pair/<impl>/<da>/<db>/<pose>: spider vs duck (assimp's sample models)
//     at four poses: overlapping / only roots overlapping, each axis-aligned
//     and rotated; and a duck 400x smaller than the spider on its surface.
//   BM_Thesis/<impl>/<set>: the mean over 200 overlapping 6-6 pairs of the
//     bundled thesis models (assets/*.obj): axis-aligned, rotated, and a small
//     object against one 20..400x larger.
//   BM_All/<impl>/<pose>: collide_all at 6-6 (no early out): box-test speed.
//   BM_Coherent/<cache>: 200 thesis pairs moving a little for 50 frames, with
//     and without a PairCache per pair.
//   BM_Separation/<pose>/<ask>: a 6-6 miss (roots-only poses) with its
//     separation worked out in full (ask 1: floor 0) or with a floor no
//     separation reaches (2: an ask that fails at once), each timed beside a
//     plain call: the cost of CollisionWorld's separation asks.
// impl 0 = collide, 1 = collide_reference. Counters: box tests per call,
// ns per box test (CPU time), hit.
//   cmake -B build-bench -DCMAKE_BUILD_TYPE=Release -DOCTBAKE_BENCH=ON
//   cmake --build build-bench --target bench_pair
//   build-bench/tests/bench_pair --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//   (--kernel=portable|avx2|avx512: measure that build of the box-test kernel)
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "build_tree.h"
#include "import.h"
#include "kernel_option.h"
#include "octbake/collide.h"
#include "seeded_random.h"

namespace octbake {
namespace {

constexpr int kDepth = 6;

struct Model {
  std::string name;
  Mesh mesh;
  ObjectTree tree;
  double radius = 1;
  Eigen::Vector3d centre;
};

Model load(const std::string& path) {
  Result<Mesh> mesh = import_mesh(path);
  if (!mesh) {
    std::fprintf(stderr, "bench_pair: %s: %s\n", path.c_str(), mesh.error().message.c_str());
    std::exit(1);
  }
  OctreeMasks masks = build_tree(*mesh, kDepth, Occupancy::surface);
  Model m;
  m.name = std::filesystem::path(path).stem().string();
  m.centre = 0.5 * (masks.bounds.min + masks.bounds.max);
  m.radius = 0.5 * (masks.bounds.max - masks.bounds.min).norm();
  TreeInfo info;
  info.bounds = masks.bounds;
  info.depth = kDepth;
  m.tree = ObjectTree(std::move(info), std::move(masks));
  m.mesh = std::move(mesh).value();
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
const std::vector<Model>& thesis_models() {
  static const std::vector<Model> all = [] {
    std::vector<std::string> paths;
    for (const auto& e : std::filesystem::directory_iterator(std::filesystem::path(OCTBAKE_SOURCE_DIR) / "assets"))
      if (e.path().extension() == ".obj") paths.push_back(e.path().string());
    std::sort(paths.begin(), paths.end());
    std::vector<Model> out;
    for (const auto& p : paths) out.push_back(load(p));
    return out;
  }();
  return all;
}

PairTest run(int impl, const PlacedTree& a, const PlacedTree& b) {
  return impl == 0 ? collide(a, b) : collide_reference(a, b);
}

// A centred at the origin with radius 1 (times `ratio` for B's radius), B's
// centre at `offset`.
std::pair<Pose, Pose> place_pair(const Model& ma, const Model& mb, const Eigen::Quaterniond& qa,
                                 const Eigen::Quaterniond& qb, const Eigen::Vector3d& offset, double b_radius = 1) {
  Pose a, b;
  a.rotation = qa;
  b.rotation = qb;
  a.scale = 1 / ma.radius;
  b.scale = b_radius / mb.radius;
  a.position = -(a.rotation * (a.scale * ma.centre));
  b.position = offset - b.rotation * (b.scale * mb.centre);
  return {a, b};
}

std::pair<Pose, Pose> spider_duck(const Eigen::Vector3d& offset, bool rotated, double duck_radius = 1) {
  const Eigen::Quaterniond qa = rotated ? Eigen::Quaterniond(Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, 2, 3).normalized()))
                                        : Eigen::Quaterniond::Identity();
  const Eigen::Quaterniond qb = rotated
                                    ? Eigen::Quaterniond(Eigen::AngleAxisd(2.1, Eigen::Vector3d(-2, 1, 0.5).normalized()))
                                    : Eigen::Quaterniond::Identity();
  return place_pair(spider(), duck(), qa, qb, offset, duck_radius);
}

// The nearest offset along a diagonal where the roots overlap but 6-6 does not.
Eigen::Vector3d roots_only_offset(bool rotated) {
  const Eigen::Vector3d dir = Eigen::Vector3d(1, 0.7, 0.4).normalized();
  for (double d = 0; d < 4; d += 0.01) {
    const auto [a, b] = spider_duck(d * dir, rotated);
    if (collide_reference({&spider().tree, a, 0}, {&duck().tree, b, 0}).hit &&
        !collide_reference({&spider().tree, a, kDepth}, {&duck().tree, b, kDepth}).hit)
      return d * dir;
  }
  std::fprintf(stderr, "bench_pair: no roots-only pose\n");
  std::exit(1);
}

// A point of the spider's surface (a vertex), in the placed spider's frame.
Eigen::Vector3d spider_surface_point(bool rotated) {
  const auto [a, b] = spider_duck({0, 0, 0}, rotated);
  (void)b;
  const Mesh& m = spider().mesh;
  return a.apply(m.positions[m.positions.size() / 3]);
}

void report(benchmark::State& state, uint64_t box_tests_per_iteration, double calls_per_iteration) {
  state.counters["box_tests"] = double(box_tests_per_iteration) / calls_per_iteration;
  state.counters["ns_per_box_test"] =
      benchmark::Counter(double(box_tests_per_iteration) * double(state.iterations()),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["us_per_call"] = benchmark::Counter(calls_per_iteration * double(state.iterations()),
                                                     benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

constexpr const char* kPoseNames[] = {"overlap", "overlap_rotated", "roots_only", "roots_only_rotated",
                                      "small_on_large", "small_on_large_rotated"};

std::pair<PlacedTree, PlacedTree> spider_duck_case(int kind, int da, int db) {
  const bool rotated = kind % 2 == 1;
  constexpr double kSmall = 1.0 / 400;
  Eigen::Vector3d offset(0.3, 0.1, 0);
  if (kind == 2 || kind == 3) offset = roots_only_offset(rotated);
  if (kind >= 4) offset = spider_surface_point(rotated);
  const auto [pa, pb] = spider_duck(offset, rotated, kind >= 4 ? kSmall : 1.0);
  return {PlacedTree{&spider().tree, pa, da}, PlacedTree{&duck().tree, pb, db}};
}

// args: impl, depth a, depth b, pose (see kPoseNames)
void BM_Pair(benchmark::State& state) {
  const int impl = int(state.range(0)), da = int(state.range(1)), db = int(state.range(2)), kind = int(state.range(3));
  const auto [a, b] = spider_duck_case(kind, da, db);
  PairTest r;
  for (auto _ : state) {
    r = run(impl, a, b);
    benchmark::DoNotOptimize(r);
  }
  report(state, r.box_tests, 1);
  state.counters["hit"] = r.hit;
  state.SetLabel(std::string(impl == 0 ? "new " : "reference ") + kPoseNames[kind]);
}

// roots_apart on the same poses, from PlacedRoots worked out beforehand (as
// CollisionWorld keeps them): the shortcut detect() takes before a pair's
// depths, to set against BM_Pair at 0-0 (collide()'s root test).
void BM_RootsApart(benchmark::State& state) {
  const auto [a, b] = spider_duck_case(int(state.range(0)), 0, 0);
  const PlacedRoot ra = placed_root(*a.tree, a.pose), rb = placed_root(*b.tree, b.pose);
  bool apart = false;
  for (auto _ : state) {
    apart = roots_apart(ra, a.pose.position, rb, b.pose.position);
    benchmark::DoNotOptimize(apart);
  }
  state.counters["apart"] = apart;
  state.counters["us_per_call"] =
      benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.SetLabel(kPoseNames[state.range(0)]);
}

// 0-0 (one box test: the roots) is the cost of a call's set-up.
void pair_args(benchmark::internal::Benchmark* b) {
  for (int kind = 0; kind < 6; ++kind)
    for (int impl = 0; impl < 2; ++impl)
      for (const auto& [da, db] : {std::pair{0, 0}, {1, 1}, {1, 6}, {2, 6}, {3, 3}, {4, 4}, {5, 5}, {6, 6}})
        b->Args({impl, da, db, kind});
}

// 200 seeded overlapping 6-6 pairs of thesis models: set 0 axis-aligned,
// 1 rotated, 2 a small object (1/20..1/400 the radius) against a large one.
const std::vector<std::pair<PlacedTree, PlacedTree>>& thesis_pairs(int set) {
  static std::vector<std::pair<PlacedTree, PlacedTree>> cache[3];
  auto& out = cache[set];
  if (!out.empty()) return out;
  const auto& ms = thesis_models();
  std::mt19937 rng(100 + set);
  while (out.size() < 200) {
    const Model &ma = ms[rng() % ms.size()], &mb = ms[rng() % ms.size()];
    const bool rotated = set >= 1;
    const Eigen::Quaterniond qa = rotated ? test::random_rotation(rng) : Eigen::Quaterniond::Identity();
    const Eigen::Quaterniond qb = rotated ? test::random_rotation(rng) : Eigen::Quaterniond::Identity();
    Eigen::Vector3d offset = 1.5 * test::uniform01(rng) * (test::random_rotation(rng) * Eigen::Vector3d::UnitX());
    double b_radius = 1;
    if (set == 2) {
      b_radius = 1 / (20 * std::pow(20.0, test::uniform01(rng)));  // 1/20 .. 1/400
      const Pose a = place_pair(ma, mb, qa, qb, {0, 0, 0}).first;
      offset = a.apply(ma.mesh.positions[rng() % ma.mesh.positions.size()]) +
               b_radius * (test::random_rotation(rng) * Eigen::Vector3d::UnitX());
    }
    const auto [pa, pb] = place_pair(ma, mb, qa, qb, offset, b_radius);
    const PlacedTree a{&ma.tree, pa, kDepth}, b{&mb.tree, pb, kDepth};
    if (collide_reference(a, b).hit) out.emplace_back(a, b);
  }
  return out;
}

constexpr const char* kSetNames[] = {"thesis_aligned", "thesis_rotated", "thesis_small_vs_large_20-400x"};

// args: impl, set
void BM_Thesis(benchmark::State& state) {
  const int impl = int(state.range(0)), set = int(state.range(1));
  const auto& pairs = thesis_pairs(set);
  uint64_t box_tests = 0;
  for (auto _ : state) {
    box_tests = 0;
    for (const auto& [a, b] : pairs) {
      const PairTest r = run(impl, a, b);
      benchmark::DoNotOptimize(r);
      box_tests += r.box_tests;
    }
  }
  report(state, box_tests, double(pairs.size()));
  state.SetLabel(std::string(impl == 0 ? "new " : "reference ") + kSetNames[set]);
}

// args: impl, pose (0 overlap, 1 overlap rotated)
void BM_All(benchmark::State& state) {
  const int impl = int(state.range(0)), kind = int(state.range(1));
  const auto [a, b] = spider_duck_case(kind, kDepth, kDepth);
  std::vector<LeafPair> leaves;
  leaves.reserve(1 << 16);
  PairTest r;
  for (auto _ : state) {
    leaves.clear();
    r = impl == 0 ? collide_all(a, b, leaves) : collide_all_reference(a, b, leaves);
    benchmark::DoNotOptimize(r);
  }
  report(state, r.box_tests, 1);
  state.counters["leaf_pairs"] = double(leaves.size());
  state.SetLabel(std::string(impl == 0 ? "new " : "reference ") + kPoseNames[kind]);
}

// args: cache (0 no, 1 yes). Frame f moves B by a small step: 0.2% of the
// pair's size per frame along a fixed direction, rotating a little.
void BM_Coherent(benchmark::State& state) {
  const bool cached = state.range(0) == 1;
  const auto& pairs = thesis_pairs(1);
  constexpr int kFrames = 50;
  std::vector<PairCache> caches(pairs.size());
  uint64_t box_tests = 0, hits = 0;
  for (auto _ : state) {
    box_tests = hits = 0;
    std::fill(caches.begin(), caches.end(), PairCache{});
    for (int f = 0; f < kFrames; ++f)
      for (size_t i = 0; i < pairs.size(); ++i) {
        PlacedTree b = pairs[i].second;
        const Eigen::Vector3d dir = Eigen::Vector3d(1, 0.5 + 0.001 * double(i), -0.3).normalized();
        b.pose.position += 0.002 * f * dir;
        b.pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.002 * f, Eigen::Vector3d::UnitZ())) * b.pose.rotation;
        const PairTest r = cached ? collide(pairs[i].first, b, caches[i]) : collide(pairs[i].first, b);
        box_tests += r.box_tests;
        hits += r.hit;
      }
  }
  report(state, box_tests, double(pairs.size() * kFrames));
  state.counters["hits"] = double(hits);
  state.SetLabel(cached ? "with PairCache" : "without cache");
}

// args: pose (2 or 3: roots only), ask (see the header). Each iteration
// times a plain call and an ask back to back (this host's speed drifts
// within seconds), so ask_over_plain is a ratio of one run.
void BM_Separation(benchmark::State& state) {
  const int kind = int(state.range(0)), ask = int(state.range(1));
  const auto [a, b] = spider_duck_case(kind, kDepth, kDepth);
  using Clock = std::chrono::steady_clock;
  PairTest r;
  double separation = 0;
  Clock::duration plain{}, asked{};
  for (auto _ : state) {
    const auto t0 = Clock::now();
    r = collide(a, b);
    benchmark::DoNotOptimize(r);
    const auto t1 = Clock::now();
    separation = ask == 1 ? 0.0 : std::numeric_limits<double>::max();
    r = collide(a, b, separation);
    benchmark::DoNotOptimize(r);
    benchmark::DoNotOptimize(separation);
    plain += t1 - t0;
    asked += Clock::now() - t1;
  }
  const double n = double(state.iterations());
  state.counters["plain_ns"] = std::chrono::duration<double, std::nano>(plain).count() / n;
  state.counters["ask_ns"] = std::chrono::duration<double, std::nano>(asked).count() / n;
  state.counters["ask_over_plain"] = double(asked.count()) / double(plain.count());
  state.counters["box_tests"] = double(r.box_tests);
  state.counters["hit"] = r.hit;
  state.counters["separation"] = separation;
  state.SetLabel(std::string(kPoseNames[kind]) + (ask == 1 ? " separation" : " failing ask"));
}

// Best of N (run with --benchmark_repetitions=N): the least disturbed run.
auto best_of = [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); };
BENCHMARK(BM_Pair)->Apply(pair_args)->ComputeStatistics("min", best_of);
BENCHMARK(BM_RootsApart)->DenseRange(0, 5)->ComputeStatistics("min", best_of);
BENCHMARK(BM_Thesis)->ArgsProduct({{0, 1}, {0, 1, 2}})->ComputeStatistics("min", best_of);
BENCHMARK(BM_All)->ArgsProduct({{0, 1}, {0, 1}})->ComputeStatistics("min", best_of);
BENCHMARK(BM_Coherent)->Arg(0)->Arg(1)->ComputeStatistics("min", best_of);
BENCHMARK(BM_Separation)->ArgsProduct({{2, 3}, {1, 2}})->ComputeStatistics("min", best_of);

}  // namespace
}  // namespace octbake

// --kernel=portable|avx2|avx512: the box-test kernel build to measure
// (kernel_option.h).
int main(int argc, char** argv) { return octbake::run_benchmarks(argc, argv, "bench_pair"); }
