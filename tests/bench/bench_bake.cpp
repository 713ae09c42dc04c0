// Baking throughput (triangles per second, one core): depth 3 / 6 / 8 x
// surface / solid / vertices, on the largest bundled asset and on a generated
// 100k-triangle torus; and the parallel build of one large mesh (a generated
// 70k-triangle "scan") at depth 10 and 12 on 1 and 2 threads, with the
// speed-up, for the build alone (BM_BakeScanSpeedup) and for the whole bake,
// build plus encode_file (BM_BakeScanWholeSpeedup: what `octbake -j1` and
// `-j2` do with one mesh). Build with -DOCTBAKE_BENCH=ON -DCMAKE_BUILD_TYPE=Release.
//   build/tests/bench_bake --benchmark_filter=BM_BakeScan
// The same scan as an OBJ file, to time the command line on it
// (`time octbake -j1 --force -d 10 -o out scan.obj`, then -j2):
//   build/tests/bench_bake --write-scan=scan.obj
#include <benchmark/benchmark.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "build_tree.h"
#include "import.h"
#include "octbake/format.h"

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

// A closed, bumpy sphere standing in for a 3D scan: a lat-long grid of
// 188 x 188 quads (70,312 triangles) whose radius wobbles on several
// frequencies, so its triangles are small and unevenly spread like a scan's.
const Mesh& scan_70k() {
  static const Mesh m = [] {
    constexpr int kRings = 188, kSegments = 188;
    Mesh mesh;
    auto radius = [](double th, double ph) {
      return 1 + 0.08 * std::sin(5 * th) * std::cos(3 * ph) + 0.03 * std::sin(17 * th + 2) * std::sin(13 * ph) +
             0.01 * std::cos(41 * th) * std::sin(37 * ph + 1);
    };
    mesh.positions.emplace_back(0, 0, radius(0, 0));
    for (int r = 1; r < kRings; ++r)
      for (int g = 0; g < kSegments; ++g) {
        const double th = std::numbers::pi * r / kRings, ph = 2 * std::numbers::pi * g / kSegments;
        const double rad = radius(th, ph);
        mesh.positions.emplace_back(rad * std::sin(th) * std::cos(ph), rad * std::sin(th) * std::sin(ph),
                                    rad * std::cos(th));
      }
    mesh.positions.emplace_back(0, 0, -radius(std::numbers::pi, 0));
    auto at = [](int r, int g) { return uint32_t(1 + (r - 1) * kSegments + g % kSegments); };
    const uint32_t south = uint32_t(mesh.positions.size() - 1);
    for (int g = 0; g < kSegments; ++g) mesh.triangles.push_back({0, at(1, g), at(1, g + 1)});
    for (int r = 1; r + 1 < kRings; ++r)
      for (int g = 0; g < kSegments; ++g) {
        mesh.triangles.push_back({at(r, g), at(r + 1, g), at(r + 1, g + 1)});
        mesh.triangles.push_back({at(r, g), at(r + 1, g + 1), at(r, g + 1)});
      }
    for (int g = 0; g < kSegments; ++g) mesh.triangles.push_back({south, at(kRings - 1, g + 1), at(kRings - 1, g)});
    return mesh;
  }();
  return m;
}

// One large mesh, depth range(0), on range(1) threads (the caller plus
// range(1) - 1 helpers): wall time, since the helpers' CPU time is not the
// caller's. Every thread count gives the same masks (checked).
void BM_BakeScan(benchmark::State& state) {
  const Mesh& mesh = scan_70k();
  const int depth = static_cast<int>(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  uint64_t leaves = 0;
  for (auto _ : state) {
    ThreadBudget budget(threads - 1);
    const OctreeMasks t = build_tree(mesh, depth, Occupancy::surface, {&budget, {}});
    leaves = t.box_count(depth);
    benchmark::DoNotOptimize(leaves);
  }
  state.counters["tris"] = double(mesh.triangles.size());
  state.counters["leaves"] = double(leaves);
}

double cpu_seconds(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

// The speed-up itself: each iteration builds once on 1 thread and once on 2
// (alternating which goes first); the counters are the best of each:
//  - t1_s, t2_s, speedup: wall time, what a user waits for (on a machine
//    loaded by other work the second thread may find no free core);
//  - cpu_speedup: 1-thread CPU time over the 2-thread run's critical path,
//    max(calling thread's CPU, the helper's CPU): the speed-up on two idle
//    cores, as far as CPU time shows it (memory-bound stalls count as CPU).
// Fails when the two builds differ.
void BM_BakeScanSpeedup(benchmark::State& state) {
  const Mesh& mesh = scan_70k();
  const int depth = static_cast<int>(state.range(0));
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double wall[2] = {kInf, kInf}, cpu1 = kInf, path2 = kInf;
  bool two_first = false;
  for (auto _ : state) {
    OctreeMasks built[2];
    for (int k = 0; k < 2; ++k) {
      const int threads = (k + two_first) % 2 + 1;
      ThreadBudget budget(threads - 1);
      const double p0 = cpu_seconds(CLOCK_PROCESS_CPUTIME_ID), t0 = cpu_seconds(CLOCK_THREAD_CPUTIME_ID);
      const auto start = std::chrono::steady_clock::now();
      built[threads - 1] = build_tree(mesh, depth, Occupancy::surface, {&budget, {}});
      const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const double process = cpu_seconds(CLOCK_PROCESS_CPUTIME_ID) - p0;
      const double own = cpu_seconds(CLOCK_THREAD_CPUTIME_ID) - t0;
      wall[threads - 1] = std::min(wall[threads - 1], secs);
      if (threads == 1)
        cpu1 = std::min(cpu1, process);
      else
        path2 = std::min(path2, std::max(own, process - own));
    }
    if (!(built[0] == built[1])) state.SkipWithError("1 and 2 threads built different masks");
    two_first = !two_first;
  }
  state.counters["t1_s"] = wall[0];
  state.counters["t2_s"] = wall[1];
  state.counters["speedup"] = wall[0] / wall[1];
  state.counters["cpu1_s"] = cpu1;
  state.counters["cpu_path2_s"] = path2;
  state.counters["cpu_speedup"] = cpu1 / path2;
}

// The whole bake of the scan on 1 and 2 threads, as octbake -j1 / -j2 runs
// it: build_tree on the budget, then encode_file (zstd level 19) on the same
// threads. Each iteration bakes once on each (alternating which goes first);
// the counters are the best of each: t1_s, t2_s, speedup (wall), and the
// encode part alone (enc1_s, enc2_s). Fails when the bytes differ.
void BM_BakeScanWholeSpeedup(benchmark::State& state) {
  const Mesh& mesh = scan_70k();
  const int depth = static_cast<int>(state.range(0));
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double wall[2] = {kInf, kInf}, encode[2] = {kInf, kInf};
  size_t bytes_out = 0;
  bool two_first = false;
  using Clock = std::chrono::steady_clock;
  for (auto _ : state) {
    std::vector<uint8_t> bytes[2];
    for (int k = 0; k < 2; ++k) {
      const int threads = (k + two_first) % 2 + 1;
      ThreadBudget budget(threads - 1);  // the calling thread holds its own slot
      const auto start = Clock::now();
      BakeOptions options;
      options.depth = depth;
      const TreeToEncode tree{"scan", "", options, mesh.triangles.size(), mesh.positions.size(),
                              build_tree(mesh, depth, Occupancy::surface, {&budget, {}})};
      const auto built = Clock::now();
      bytes[threads - 1] = encode_file({&tree, 1}, "bench", std::min(threads, encode_threads_useful({&tree, 1})));
      const auto end = Clock::now();
      wall[threads - 1] = std::min(wall[threads - 1], std::chrono::duration<double>(end - start).count());
      encode[threads - 1] = std::min(encode[threads - 1], std::chrono::duration<double>(end - built).count());
    }
    if (bytes[0] != bytes[1]) state.SkipWithError("1 and 2 threads wrote different bytes");
    bytes_out = bytes[0].size();
    two_first = !two_first;
  }
  state.counters["t1_s"] = wall[0];
  state.counters["t2_s"] = wall[1];
  state.counters["speedup"] = wall[0] / wall[1];
  state.counters["enc1_s"] = encode[0];
  state.counters["enc2_s"] = encode[1];
  state.counters["bytes"] = double(bytes_out);
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
BENCHMARK(BM_BakeScan)
    ->ArgsProduct({{10, 12}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK(BM_BakeScanSpeedup)->Arg(10)->Arg(12)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
BENCHMARK(BM_BakeScanWholeSpeedup)->Arg(10)->Arg(12)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

// The scan as OBJ text (exact: 17 significant digits).
bool write_obj(const Mesh& mesh, const char* path) {
  FILE* f = std::fopen(path, "w");
  if (!f) return false;
  for (const auto& p : mesh.positions) std::fprintf(f, "v %.17g %.17g %.17g\n", p.x(), p.y(), p.z());
  for (const auto& t : mesh.triangles) std::fprintf(f, "f %u %u %u\n", t[0] + 1, t[1] + 1, t[2] + 1);
  return std::fclose(f) == 0;
}

}  // namespace
}  // namespace octbake

int main(int argc, char** argv) {
  const std::string flag = "--write-scan=";
  if (argc == 2 && std::string(argv[1]).rfind(flag, 0) == 0) {
    const std::string path = std::string(argv[1]).substr(flag.size());
    if (octbake::write_obj(octbake::scan_70k(), path.c_str())) return 0;
    std::fprintf(stderr, "bench_bake: %s: cannot write\n", path.c_str());
    return 1;
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
