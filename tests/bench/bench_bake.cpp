// Baking throughput (triangles per second, one core): depth 3 / 6 / 8 x
// surface / solid / vertices, on the largest bundled asset and on a generated
// 100k-triangle torus. Build with -DOCTBAKE_BENCH=ON -DCMAKE_BUILD_TYPE=Release.
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <string>

#include "build_tree.h"
#include "import.h"

namespace octbake {
namespace {

// Torus, major radius 1, minor 0.35: 2 * rings * sides triangles, closed.
Mesh torus(int rings, int sides) {
  Mesh m;
  for (int i = 0; i < rings; ++i) {
    const double u = 2 * std::numbers::pi * i / rings;
    for (int j = 0; j < sides; ++j) {
      const double v = 2 * std::numbers::pi * j / sides;
      const double r = 1 + 0.35 * std::cos(v);
      m.positions.emplace_back(r * std::cos(u), 0.35 * std::sin(v), r * std::sin(u));
    }
  }
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < sides; ++j) {
      const uint32_t a = i * sides + j, b = i * sides + (j + 1) % sides;
      const uint32_t c = ((i + 1) % rings) * sides + j, d = ((i + 1) % rings) * sides + (j + 1) % sides;
      m.triangles.push_back({a, c, b});
      m.triangles.push_back({b, c, d});
    }
  return m;
}

const Mesh& torus_100k() {
  static const Mesh m = torus(/*rings=*/500, /*sides=*/100);
  return m;
}

const Mesh& elephant() {
  static const Mesh m = [] {
    Result<Mesh> r = import_mesh(std::string(OCTBAKE_SOURCE_DIR) + "/assets/elephant.obj");
    return r.ok() ? std::move(r).value() : Mesh{};
  }();
  return m;
}

void bake(benchmark::State& state, const Mesh& mesh) {
  if (mesh.triangles.empty()) {
    state.SkipWithError("mesh not loaded");
    return;
  }
  const int depth = static_cast<int>(state.range(0));
  const auto mode = static_cast<Occupancy>(state.range(1));
  uint64_t leaves = 0;
  for (auto _ : state) {
    const OctreeMasks t = build_tree(mesh, depth, mode);
    leaves = t.box_count(depth);
    benchmark::DoNotOptimize(leaves);
  }
  state.SetLabel(to_string(mode));
  state.counters["tris"] = double(mesh.triangles.size());
  state.counters["leaves"] = double(leaves);
  state.counters["tris_per_s"] =
      benchmark::Counter(double(mesh.triangles.size()), benchmark::Counter::kIsIterationInvariantRate);
}

void BM_BakeElephant(benchmark::State& s) { bake(s, elephant()); }
void BM_BakeTorus100k(benchmark::State& s) { bake(s, torus_100k()); }

void modes(benchmark::internal::Benchmark* b) {
  for (int depth : {3, 6, 8})
    for (int mode : {0, 1, 2}) b->Args({depth, mode});
  b->Unit(benchmark::kMillisecond);
}

BENCHMARK(BM_BakeElephant)->Apply(modes);
BENCHMARK(BM_BakeTorus100k)->Apply(modes);

}  // namespace
}  // namespace octbake

BENCHMARK_MAIN();
