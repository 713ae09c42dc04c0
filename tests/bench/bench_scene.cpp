// Reading a scene file: parse_scene() on scenes of 1,000 to 100,000 objects
// (write_scene's text, objects on a grid, a tenth moving and spinning). The
// time per object should not grow with the object count: nlohmann's callback
// parser made it quadratic (100,000 objects 2.7 s, 12,500 0.16 s; see
// PathTracker in octscene/scene.cpp).
//   ./build/tests/bench_scene
#include <benchmark/benchmark.h>

#include <cmath>
#include <string>

#include "scene.h"

namespace octbake::scene {
namespace {

std::string scene_text(int objects) {
  Scene s;
  s.world = Aabb{Eigen::Vector3d::Constant(-1e4), Eigen::Vector3d::Constant(1e4)};
  s.frames = 100;
  s.camera.position = {0, 50, -200};
  const int side = int(std::ceil(std::cbrt(double(objects))));
  for (int i = 0; i < objects; ++i) {
    SceneObject o;
    o.name = "model_" + std::to_string(i);
    o.model = i % 2 ? "tree" : "car";
    o.pose.position = {10.0 * (i % side), 10.0 * (i / side % side), 10.0 * (i / side / side)};
    o.pose.scale = 1 + 0.001 * (i % 7);
    if (i % 10 == 0) o.velocity = {0.5, 0, -0.25}, o.angular_velocity = {0, 1.5, 0};
    s.objects.push_back(o);
  }
  return write_scene(s, "baked");
}

void BM_ParseScene(benchmark::State& state) {
  const int objects = int(state.range(0));
  const std::string text = scene_text(objects);
  for (auto _ : state) {
    Result<Scene> s = parse_scene(text, ".");
    if (!s || s->objects.size() != size_t(objects)) {
      state.SkipWithError(s ? "wrong object count" : s.error().message.c_str());
      return;
    }
    benchmark::DoNotOptimize(s);
  }
  state.counters["bytes"] = double(text.size());
  state.SetItemsProcessed(state.iterations() * objects);  // objects per second
}
BENCHMARK(BM_ParseScene)->ArgName("objects")->Arg(1'000)->Arg(10'000)->Arg(100'000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace octbake::scene

BENCHMARK_MAIN();
