// Pixel area per posed box, the per-object cost of the screen and thesis LOD
// policies: boxes wholly in front of the camera (the projected-hull path),
// boxes straddling the near plane (3D clipping), and boxes behind the camera;
// and the lower and upper bounds the screen policy tries first.
//   build/tests/bench_lod
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "octbake/lod.h"

namespace octbake {
namespace {

enum class Placement { ahead, straddling, behind };

std::vector<OrientedBox> boxes(Placement where) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<OrientedBox> out;
  for (int i = 0; i < 1024; ++i) {
    OrientedBox b;
    const double z = where == Placement::ahead ? 20 + 10 * u(rng) : where == Placement::behind ? -30 + 5 * u(rng) : -10;
    b.center = {8 * u(rng), 4 * u(rng), z};  // camera at (0, 0, -10) looking down +z
    b.axes = Eigen::Quaterniond(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized()).toRotationMatrix();
    b.half = Eigen::Vector3d(1 + u(rng) * 0.5, 1 + u(rng) * 0.5, 1 + u(rng) * 0.5);
    if (where == Placement::straddling) b.center.x() += 1.5;  // not enclosing the camera
    out.push_back(b);
  }
  return out;
}

void BM_PixelArea(benchmark::State& state) {
  const auto where = static_cast<Placement>(state.range(0));
  const std::vector<OrientedBox> in = boxes(where);
  const Camera camera;
  size_t k = 0;
  double sum = 0;
  for (auto _ : state) {
    sum += pixel_area(camera, in[k++ & 1023]);
    benchmark::DoNotOptimize(sum);
  }
  state.SetLabel(where == Placement::ahead ? "ahead" : where == Placement::behind ? "behind" : "straddling near plane");
}
BENCHMARK(BM_PixelArea)->Arg(0)->Arg(1)->Arg(2);

// The same with the camera prepared once, as CollisionWorld does per frame.
void BM_PixelAreaPreparedView(benchmark::State& state) {
  const auto where = static_cast<Placement>(state.range(0));
  const std::vector<OrientedBox> in = boxes(where);
  const CameraView view{Camera{}};
  size_t k = 0;
  double sum = 0;
  for (auto _ : state) {
    sum += pixel_area(view, in[k++ & 1023]);
    benchmark::DoNotOptimize(sum);
  }
}
BENCHMARK(BM_PixelAreaPreparedView)->Arg(0)->Arg(1)->Arg(2);

// The bounds the screen policy tries before the exact area (prepared view):
// arg 0 the lower bound, 1 the upper bound.
void BM_PixelAreaBound(benchmark::State& state) {
  const auto where = static_cast<Placement>(state.range(0));
  const bool upper = state.range(1) != 0;
  const std::vector<OrientedBox> in = boxes(where);
  const CameraView view{Camera{}};
  size_t k = 0;
  double sum = 0;
  for (auto _ : state) {
    const OrientedBox& b = in[k++ & 1023];
    sum += upper ? pixel_area_upper_bound(view, b) : pixel_area_lower_bound(view, b);
    benchmark::DoNotOptimize(sum);
  }
  state.SetLabel(upper ? "upper" : "lower");
}
BENCHMARK(BM_PixelAreaBound)->ArgsProduct({{0, 1, 2}, {0, 1}});

}  // namespace
}  // namespace octbake

BENCHMARK_MAIN();
