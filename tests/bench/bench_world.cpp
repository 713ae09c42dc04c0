// World::step per frame: N solid-box objects (trees of depth 3..6) on a
// jittered lattice of constant spacing, so density does not change with N; a
// third move at ~2 units/s, separate response, screen LOD, world cells about
// one spacing wide.
//
// The app-driven CollisionWorld on the same scenes (BM_Detect): every pose
// set by the app each frame (a third moving, a tenth spinning), the camera
// moving every frame, set_pose (or one set_poses: batch:1) + detect() timed; against FCL's
// DynamicAABBTree (setTransform + computeAABB of every object, update(),
// collide() with the exact OBBRSS BVH test of the box meshes) on the same
// poses (BM_FclDynamicAabb), and against the World::step of commit 68d2b0b
// with its fixed camera (BM_LegacyStep, tests/bench/legacy_world.h).
// Heap allocations per timed frame are counted by replacing operator new;
// frame_median_us is the median timed frame (compare thread counts by it).
// BM_PoolJob: the cost of one job on the built-in thread pool (see there).
//
// Run: build with -DOCTBAKE_BENCH=ON, then
//   ./build/tests/bench_world --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//   [--kernel=portable|avx2|avx512]
// operator new/delete are replaced below (malloc/free): GCC 12 then flags
// every inlined delete as "mismatched" though the pair is consistent.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#include <benchmark/benchmark.h>
#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/narrowphase/collision.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <new>
#include <numbers>
#include <random>
#include <thread>
#include <vector>

#include "kernel_option.h"
#include "legacy_world.h"
#include "octbake/collision_world.h"
#include "octbake/world.h"

// Every heap allocation of the process, for the allocations-per-frame counter.
static std::atomic<uint64_t> g_allocations{0};
void* operator new(size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](size_t n) { return operator new(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }
void operator delete[](void* p, size_t) noexcept { std::free(p); }

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
    total.pairs_reused += f.pairs_reused;
    total.box_tests += f.box_tests;
    total.collisions += f.collisions;
    total.area_refreshes += f.area_refreshes;
  }
  reinsertions = world.world_tree().reinsertions() - reinsertions;
  const double frames = double(state.iterations());
  state.counters["pair_tests"] = double(total.pair_tests) / frames;
  state.counters["pairs_reused"] = double(total.pairs_reused) / frames;
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

// The box-filtered broadphase with many objects too big for their cells
// (overflow), in a 256-wide world of depth 8, shapes chosen around the cost
// guard of the overflow pairing (WorldTree::pair_overflow_by_coarse_cells):
// 0: 1,000 small + 500 overflow (12-40 cells wide) + 4 huge: coarse cells pay;
// 1: 3,000 small + 100 overflow ~110 cells wide: pairing with all is cheaper;
// 2: 2,000 small + 1,000 overflow 28 cells wide in one spot: they share
//    coarse cells so much that pairing with all is cheaper;
// 3: 10,000 small + 40 overflow: coarse cells pay.
void BM_OverflowPairs(benchmark::State& state) {
  const int shape = int(state.range(0));
  std::mt19937 rng(77);
  const auto uniform = [&](double lo, double hi) { return lo + (hi - lo) * unit(rng); };
  const auto box = [&](double lo, double hi, double spill) {
    const Eigen::Vector3d h(uniform(lo, hi), uniform(lo, hi), uniform(lo, hi));
    const Eigen::Vector3d c(uniform(-spill, 256 + spill), uniform(-spill, 256 + spill), uniform(-spill, 256 + spill));
    return Aabb{c - h, c + h};
  };
  std::vector<Aabb> boxes;
  const auto add = [&](int n, double lo, double hi, double spill) {
    for (int i = 0; i < n; ++i) boxes.push_back(box(lo, hi, spill));
  };
  if (shape == 0) add(1000, 0.1, 2, 4), add(500, 6, 20, 10), add(4, 90, 140, 0);
  if (shape == 1) add(3000, 0.1, 2, 4), add(100, 50, 60, 0);
  if (shape == 2) {
    add(2000, 0.1, 2, 4);
    for (int i = 0; i < 1000; ++i) {
      const Eigen::Vector3d c(uniform(120, 136), uniform(120, 136), uniform(120, 136));
      boxes.push_back({c.array() - 14, c.array() + 14});
    }
  }
  if (shape == 3) add(10000, 0.1, 2, 4), add(40, 6, 10, 10);
  WorldTree tree(Aabb{Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(256)}, 8);
  for (uint32_t i = 0; i < boxes.size(); ++i) tree.update(i, boxes[i]);
  std::vector<std::pair<uint32_t, uint32_t>> pairs;
  for (auto _ : state) {
    tree.overlapping_pairs(boxes, pairs);
    benchmark::DoNotOptimize(pairs.data());
  }
  state.counters["pairs"] = double(pairs.size());
  state.counters["overflow"] = double(tree.overflow_ids().size());
}
BENCHMARK(BM_OverflowPairs)->ArgName("shape")->DenseRange(0, 3)->Unit(benchmark::kMicrosecond);

// ---- the app-driven world ----

constexpr double kDt = 1.0 / 30.0;
constexpr int64_t kWarmup = 190;

// The app's own motion: a third oscillate (bounded, so long runs stay in the
// world), a tenth spin; every pose is recomputed and set each frame.
struct AppMotion {
  std::vector<Pose> start;
  std::vector<Eigen::Vector3d> velocity, spin;
  std::vector<Pose> now;

  explicit AppMotion(const Scene& s) {
    std::mt19937 rng(7);
    for (size_t i = 0; i < s.objects.size(); ++i) {
      start.push_back(s.objects[i].pose);
      velocity.push_back(s.objects[i].velocity);
      const Eigen::Vector3d axis(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
      spin.push_back(i % 10 == 1 ? Eigen::Vector3d(axis.normalized() * 1.5) : Eigen::Vector3d::Zero());
    }
    now = start;
  }
  void at(int64_t f) {
    const double t = double(f) * kDt;
    for (size_t i = 0; i < now.size(); ++i) {
      now[i].position = start[i].position + velocity[i] * std::sin(t);
      if (!spin[i].isZero(0))
        now[i].rotation = Eigen::Quaterniond(Eigen::AngleAxisd(spin[i].norm() * t, spin[i].normalized())) * start[i].rotation;
    }
  }
  static Camera camera(const Scene& s, int64_t f) {
    Camera c = s.settings.camera;
    const double a = 0.01 * double(f), r = c.position.z() - c.look_at.z();
    c.position = c.look_at + Eigen::Vector3d(r * std::sin(a), 0.2 * r, r * std::cos(a));
    return c;
  }
};

CollisionSettings collision_settings(const Scene& s, LodPolicy policy) {
  CollisionSettings c;
  c.bounds = s.settings.bounds;
  c.world_depth = s.settings.world_depth;
  c.lod = s.settings.lod;
  c.lod.policy = policy;
  c.camera = s.settings.camera;
  return c;
}

// Wall time of each timed frame. Their median is the counter to compare
// thread counts by on a shared host: other tenants' bursts move the mean
// (±15% between identical runs here) far more than the median.
class FrameTimes {
 public:
  explicit FrameTimes(const benchmark::State& state) { us_.reserve(size_t(state.max_iterations)); }
  void start() { t0_ = std::chrono::steady_clock::now(); }
  // Returns the frame's time in µs.
  double stop() {
    us_.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0_).count());
    return us_.back();
  }
  double median() {
    if (us_.empty()) return 0;
    std::nth_element(us_.begin(), us_.begin() + ptrdiff_t(us_.size() / 2), us_.end());
    return us_[us_.size() / 2];
  }

 private:
  std::vector<double> us_;
  std::chrono::steady_clock::time_point t0_;
};

// The same counters for every case of the detect comparison (the CSV
// reporter needs one set of columns).
void set_counters(benchmark::State& state, const DetectStats& total, uint64_t allocations, FrameTimes& times) {
  state.counters["frame_median_us"] = times.median();
  const double frames = double(state.iterations());
  state.counters["pair_tests"] = double(total.pair_tests) / frames;
  state.counters["pairs_reused"] = double(total.pairs_reused) / frames;
  state.counters["box_tests"] = double(total.box_tests) / frames;
  state.counters["contacts"] = double(total.contacts) / frames;
  state.counters["area_computations"] = double(total.area_computations) / frames;
  state.counters["allocs_per_frame"] = double(allocations) / frames;
}

// The app's frames on `scene`: its poses (set_poses, or a set_pose loop),
// its camera, detect(); timed after a warm-up.
void detect_frames(benchmark::State& state, const Scene& scene, const CollisionSettings& settings, bool batch) {
  CollisionWorld world(settings);
  std::vector<ObjectHandle> handles;
  for (const ObjectDesc& o : scene.objects) handles.push_back(world.create(TreeSource::fixed(o.tree), o.pose).value());
  AppMotion motion(scene);
  std::vector<Contact> contacts;
  // Warm up for one period of the motion (2 pi / 1 rad/s at 30 fps): every
  // WorldTree cell the motion reaches and every scratch buffer exist, so the
  // timed frames are the steady state.
  int64_t f = 0;
  const auto set_poses = [&] {
    if (batch) {
      (void)world.set_poses(handles, motion.now);
    } else {
      for (size_t i = 0; i < handles.size(); ++i) (void)world.set_pose(handles[i], motion.now[i]);
    }
  };
  for (; f < kWarmup; ++f) {
    motion.at(f);
    set_poses();
    world.set_camera(AppMotion::camera(scene, f));
    world.detect(contacts);
  }
  DetectStats total;
  uint64_t allocations = 0;
  FrameTimes times(state);
  for (auto _ : state) {
    state.PauseTiming();
    motion.at(f);
    const Camera camera = AppMotion::camera(scene, f);
    ++f;
    const uint64_t before = g_allocations.load();
    state.ResumeTiming();
    times.start();
    set_poses();
    world.set_camera(camera);
    const DetectStats d = world.detect(contacts);
    times.stop();
    state.PauseTiming();
    allocations += g_allocations.load() - before;
    total.pair_tests += d.pair_tests;
    total.pairs_reused += d.pairs_reused;
    total.box_tests += d.box_tests;
    total.contacts += d.contacts;
    total.area_computations += d.area_computations;
    state.ResumeTiming();
  }
  set_counters(state, total, allocations, times);
}

void BM_Detect(benchmark::State& state) {
  const Scene scene = make_scene(int(state.range(0)));
  CollisionSettings settings = collision_settings(scene, LodPolicy(state.range(1)));
  settings.threads = int(state.range(2));  // detect()'s parallel parts on this many threads
  const bool batch = state.range(3) != 0;  // set_poses (parallel) instead of a set_pose loop
  detect_frames(state, scene, settings, batch);
}
// Fixed frame counts, so every case (and FCL) sees exactly the same poses.
constexpr int kFrames10k = 300, kFrames100k = 40;
BENCHMARK(BM_Detect)
    ->ArgsProduct({{10'000}, {int(LodPolicy::screen), int(LodPolicy::fixed)}, {1, 2}, {0, 1}})
    ->ArgNames({"objects", "policy", "threads", "batch"})
    ->Iterations(kFrames10k)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Detect)
    ->ArgsProduct({{100'000}, {int(LodPolicy::screen), int(LodPolicy::fixed)}, {1, 2}, {0, 1}})
    ->ArgNames({"objects", "policy", "threads", "batch"})
    ->Iterations(kFrames100k)
    ->Unit(benchmark::kMicrosecond);

// Static scenery at rest: BM_Detect's scene (set_poses, one thread) with
// every third object placed against the static one before it, so a third of
// the objects rest in contact and never move. With coherence, a pair whose
// objects kept their poses and depths reuses last frame's answer; without,
// every pair is tested every frame. Screen LOD under the moving camera
// changes some depths each frame (those pairs are tested again); fixed LOD
// none.
void BM_Resting(benchmark::State& state) {
  Scene scene = make_scene(int(state.range(0)));
  for (size_t i = 2; i < scene.objects.size(); i += 3)
    scene.objects[i].pose.position = scene.objects[i - 1].pose.position + Eigen::Vector3d(0.6, 0.1, 0);
  CollisionSettings settings = collision_settings(scene, LodPolicy(state.range(1)));
  settings.coherence = state.range(2) != 0;
  detect_frames(state, scene, settings, /*batch=*/true);
}
BENCHMARK(BM_Resting)
    ->ArgsProduct({{10'000}, {int(LodPolicy::screen), int(LodPolicy::fixed)}, {1, 0}})
    ->ArgNames({"objects", "policy", "coherence"})
    ->Iterations(kFrames10k)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Resting)
    ->ArgsProduct({{100'000}, {int(LodPolicy::screen), int(LodPolicy::fixed)}, {1, 0}})
    ->ArgNames({"objects", "policy", "coherence"})
    ->Iterations(kFrames100k)
    ->Unit(benchmark::kMicrosecond);

// Objects coming and going: every frame a hundredth of the objects is
// destroyed (random ones) and as many are created at random places in the
// world, then detect() runs (one thread, app-set camera fixed). The frame
// the app sees: its destroys, creates and the detect.
void BM_Churn(benchmark::State& state) {
  const Scene scene = make_scene(int(state.range(0)));
  CollisionWorld world(collision_settings(scene, LodPolicy::screen));
  std::vector<ObjectHandle> live;
  for (const ObjectDesc& o : scene.objects) live.push_back(world.create(TreeSource::fixed(o.tree), o.pose).value());
  std::vector<Contact> contacts;
  world.detect(contacts);
  std::mt19937 rng(9);
  const size_t churn = live.size() / 100;
  const double extent = scene.settings.bounds.max.x();
  uint64_t allocations = 0;
  for (auto _ : state) {
    const uint64_t before = g_allocations.load();
    for (size_t k = 0; k < churn; ++k) {
      const size_t i = rng() % live.size();
      (void)world.destroy(live[i]);
      Pose pose;
      pose.position = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * extent;
      live[i] = world.create(TreeSource::fixed(&scene.trees[rng() % scene.trees.size()]), pose).value();
    }
    world.detect(contacts);
    allocations += g_allocations.load() - before;
  }
  state.counters["churn_per_frame"] = double(churn);
  state.counters["allocs_per_frame"] = double(allocations) / double(state.iterations());
}
BENCHMARK(BM_Churn)->ArgName("objects")->Arg(10'000)->Arg(100'000)->Unit(benchmark::kMicrosecond);

// Two threads against one, paired: two worlds on the same poses, one on one
// thread and one on two, taking turns in blocks of kPairedBlock frames (which
// side goes first alternates), so both sides see the same minutes of a shared,
// noisy host. (BM_Detect runs minutes apart gave the same code one-thread
// medians from 520 to 2,020 µs at 10k objects: a ratio of two such runs says
// more about the host than about the code.) The first frame of each block is
// not counted: the other world has just evicted this one's data from the
// caches (frames of worlds alternating every frame took 1.8-2.7x longer),
// and BM_Detect's frames are warm. Reports each side's median frame,
// `speedup` (one thread's median over two threads') and the host's core
// round trip before and after (below); the two worlds' contacts are compared
// at the end of every block and must be identical.
constexpr int64_t kPairedBlock = 8;

// The host's cache-line round trip between two threads (one atomic bounced
// 20,000 times), reported beside the speedup: on this shared VM it moved
// between ~100 and ~450 ns from minute to minute (the two vCPUs on near or
// far cores), and the 10k speedup with it, for the same binary. 0 on one
// core, where the two spinning threads would hand over once per time slice.
double core_round_trip_ns() {
  if (std::thread::hardware_concurrency() < 2) return 0;
  constexpr int kTrips = 20'000;
  alignas(64) std::atomic<int> ball{0};
  std::thread other([&] {
    for (int i = 0; i < kTrips; ++i) {
      while (ball.load(std::memory_order_acquire) != 2 * i + 1) {}
      ball.store(2 * i + 2, std::memory_order_release);
    }
  });
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < kTrips; ++i) {
    ball.store(2 * i + 1, std::memory_order_release);
    while (ball.load(std::memory_order_acquire) != 2 * i + 2) {}
  }
  const auto end = std::chrono::steady_clock::now();
  other.join();
  return std::chrono::duration<double, std::nano>(end - start).count() / kTrips;
}

// The paired benchmarks' counters: both median frames, their ratio, and the
// host's core round trip before and after the frames (see core_round_trip_ns).
void set_paired_counters(benchmark::State& state, FrameTimes (&times)[2], double round_trip_before) {
  const double one = times[0].median(), two = times[1].median();
  state.counters["one_thread_median_us"] = one;
  state.counters["two_threads_median_us"] = two;
  state.counters["speedup"] = one / two;
  state.counters["round_trip_ns_before"] = round_trip_before;
  state.counters["round_trip_ns_after"] = core_round_trip_ns();
}

void BM_ThreadsPaired(benchmark::State& state) {
  const Scene scene = make_scene(int(state.range(0)));
  const LodPolicy policy = LodPolicy(state.range(1));
  struct Side {
    std::unique_ptr<CollisionWorld> world;
    std::vector<ObjectHandle> handles;
    std::vector<Contact> contacts;
  };
  Side sides[2];
  for (int t = 0; t < 2; ++t) {
    CollisionSettings settings = collision_settings(scene, policy);
    settings.threads = t + 1;
    sides[t].world = std::make_unique<CollisionWorld>(settings);
    for (const ObjectDesc& o : scene.objects)
      sides[t].handles.push_back(sides[t].world->create(TreeSource::fixed(o.tree), o.pose).value());
  }
  AppMotion motion(scene);
  const auto frame = [&](Side& side, int64_t f) {
    (void)side.world->set_poses(side.handles, motion.now);
    side.world->set_camera(AppMotion::camera(scene, f));
    side.world->detect(side.contacts);
  };
  for (int64_t f = 0; f < kWarmup; ++f) {
    motion.at(f);
    for (Side& side : sides) frame(side, f);
  }
  FrameTimes times[2] = {FrameTimes(state), FrameTimes(state)};
  const auto same = [](const Contact& x, const Contact& y) {
    return x.a.slot == y.a.slot && x.b.slot == y.b.slot && x.depth_a == y.depth_a && x.depth_b == y.depth_b &&
           x.box_tests == y.box_tests;
  };
  int64_t block = 0;
  const double round_trip_before = core_round_trip_ns();
  for (auto _ : state) {
    const int64_t first = kWarmup + block * kPairedBlock;
    for (int k = 0; k < 2; ++k) {
      const int t = int((block + k) % 2);
      for (int64_t f = first; f < first + kPairedBlock; ++f) {
        motion.at(f);
        if (f > first) times[t].start();
        frame(sides[t], f);
        if (f > first) times[t].stop();
      }
    }
    ++block;
    if (!std::equal(sides[0].contacts.begin(), sides[0].contacts.end(), sides[1].contacts.begin(),
                    sides[1].contacts.end(), same)) {
      state.SkipWithError("one and two threads gave different contacts");
      return;
    }
  }
  set_paired_counters(state, times, round_trip_before);
}
BENCHMARK(BM_ThreadsPaired)
    ->ArgsProduct({{10'000}, {int(LodPolicy::screen), int(LodPolicy::fixed)}})
    ->ArgNames({"objects", "policy"})
    ->Iterations(kFrames10k / kPairedBlock)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ThreadsPaired)
    ->ArgsProduct({{100'000}, {int(LodPolicy::screen), int(LodPolicy::fixed)}})
    ->ArgNames({"objects", "policy"})
    ->Iterations(kFrames100k / 4)  // 10 blocks
    ->Unit(benchmark::kMillisecond);

// World::step (the simulation layer octscene runs) on one thread and on two,
// paired as BM_ThreadsPaired: the same scenes with a tenth of the objects
// spinning and the camera flying a loop, so every frame recomputes every
// object's pixel area (the layer's historic rule) and moves a third of them.
// Both worlds step the same frames; their collisions must be identical.
void BM_WorldStepThreads(benchmark::State& state) {
  Scene scene = make_scene(int(state.range(0)));
  const double extent = scene.settings.bounds.max.x();
  for (size_t i = 1; i < scene.objects.size(); i += 10) scene.objects[i].angular_velocity = {0, 1.5, 0.5};
  for (int k = 0; k <= 8; ++k) {  // a loop around the centre, 1 key per 30 frames
    const double a = k * std::numbers::pi / 4;
    scene.settings.camera_path.push_back(
        {30 * k, Eigen::Vector3d(extent / 2 + extent * std::cos(a), extent * 0.6, extent / 2 + extent * std::sin(a)),
         Eigen::Vector3d::Constant(extent / 2)});
  }
  std::unique_ptr<World> worlds[2];
  std::vector<Collision> collisions[2];
  for (int t = 0; t < 2; ++t) {
    WorldSettings settings = scene.settings;
    settings.threads = t + 1;
    worlds[t] = std::make_unique<World>(settings, scene.objects);
    worlds[t]->step(collisions[t]);  // frame 0 computes every pixel area
  }
  FrameTimes times[2] = {FrameTimes(state), FrameTimes(state)};
  int64_t block = 0;
  const double round_trip_before = core_round_trip_ns();
  for (auto _ : state) {
    for (int k = 0; k < 2; ++k) {
      const int t = int((block + k) % 2);
      for (int64_t f = 0; f < kPairedBlock; ++f) {
        times[t].start();
        worlds[t]->step(collisions[t]);
        times[t].stop();
      }
    }
    ++block;
    const auto same = [](const Collision& x, const Collision& y) {
      return x.a == y.a && x.b == y.b && x.depth_a == y.depth_a && x.depth_b == y.depth_b && x.box_tests == y.box_tests;
    };
    if (!std::equal(collisions[0].begin(), collisions[0].end(), collisions[1].begin(), collisions[1].end(), same)) {
      state.SkipWithError("one and two threads gave different collisions");
      return;
    }
  }
  set_paired_counters(state, times, round_trip_before);
  state.counters["collisions"] = double(collisions[0].size());
}
BENCHMARK(BM_WorldStepThreads)->ArgName("objects")->Arg(10'000)->Iterations(20)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_WorldStepThreads)->ArgName("objects")->Arg(100'000)->Iterations(4)->Unit(benchmark::kMillisecond);

// FCL on the same poses: a 12-triangle box mesh per tree (the solid trees are
// exactly their root boxes), OBBRSS BVHs, DynamicAABBTree broadphase.
using Bvh = fcl::BVHModel<fcl::OBBRSSd>;

std::shared_ptr<Bvh> box_bvh(const Aabb& b) {
  std::vector<fcl::Vector3d> v;
  for (int j = 0; j < 8; ++j)
    v.emplace_back(j & 1 ? b.max.x() : b.min.x(), j & 2 ? b.max.y() : b.min.y(), j & 4 ? b.max.z() : b.min.z());
  const int faces[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
  std::vector<fcl::Triangle> t;
  for (const auto& q : faces) t.emplace_back(q[0], q[1], q[2]), t.emplace_back(q[0], q[2], q[3]);
  auto bvh = std::make_shared<Bvh>();
  bvh->beginModel(int(t.size()), int(v.size()));
  bvh->addSubModel(v, t);
  bvh->endModel();
  bvh->computeLocalAABB();
  return bvh;
}

fcl::Transform3d to_fcl(const Pose& p) {
  fcl::Transform3d t = fcl::Transform3d::Identity();
  t.linear() = p.rotation.toRotationMatrix();
  t.translation() = p.position;
  return t;
}

bool exact_pair(fcl::CollisionObjectd* a, fcl::CollisionObjectd* b, void* hits) {
  const fcl::CollisionRequestd request(1, false);
  fcl::CollisionResultd result;
  fcl::collide(a, b, request, result);
  *static_cast<uint64_t*>(hits) += result.isCollision();
  return false;
}

void BM_FclDynamicAabb(benchmark::State& state) {
  const Scene scene = make_scene(int(state.range(0)));
  std::vector<std::shared_ptr<Bvh>> bvhs;
  for (const ObjectTree& t : scene.trees) bvhs.push_back(box_bvh(t.bounds()));
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> objects;
  std::vector<fcl::CollisionObjectd*> raw;
  for (const ObjectDesc& o : scene.objects) {
    objects.push_back(std::make_unique<fcl::CollisionObjectd>(bvhs[size_t(o.tree - scene.trees.data())], to_fcl(o.pose)));
    raw.push_back(objects.back().get());
  }
  fcl::DynamicAABBTreeCollisionManagerd manager;
  manager.registerObjects(raw);
  manager.setup();
  AppMotion motion(scene);
  int64_t f = kWarmup - 3;
  uint64_t hits = 0, allocations = 0;
  for (; f < kWarmup; ++f) {  // the same timed frames as BM_Detect
    motion.at(f);
    for (size_t i = 0; i < objects.size(); ++i) {
      objects[i]->setTransform(to_fcl(motion.now[i]));
      objects[i]->computeAABB();
    }
    manager.update();
  }
  FrameTimes times(state);
  for (auto _ : state) {
    state.PauseTiming();
    motion.at(f++);
    state.ResumeTiming();
    times.start();
    for (size_t i = 0; i < objects.size(); ++i) {
      objects[i]->setTransform(to_fcl(motion.now[i]));
      objects[i]->computeAABB();
    }
    const uint64_t before = g_allocations.load();
    manager.update();
    manager.collide(&hits, exact_pair);
    allocations += g_allocations.load() - before;
    times.stop();
  }
  DetectStats total;
  total.contacts = hits;
  set_counters(state, total, allocations, times);
}
BENCHMARK(BM_FclDynamicAabb)->ArgName("objects")->Arg(10'000)->Iterations(kFrames10k)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FclDynamicAabb)->ArgName("objects")->Arg(100'000)->Iterations(kFrames100k)->Unit(benchmark::kMicrosecond);

// The World::step of commit 68d2b0b (fixed camera, its own motion).
void BM_LegacyStep(benchmark::State& state) {
  Scene scene = make_scene(int(state.range(0)));
  legacy::World world(scene.settings, scene.objects);
  std::vector<Collision> collisions;
  for (int f = 0; f < kWarmup; ++f) {
    collisions.clear();
    world.step(collisions);
  }
  DetectStats total;
  uint64_t allocations = 0;
  FrameTimes times(state);
  for (auto _ : state) {
    collisions.clear();
    times.start();
    const uint64_t before = g_allocations.load();
    const FrameStats s = world.step(collisions);
    allocations += g_allocations.load() - before;
    times.stop();
    total.pair_tests += s.pair_tests, total.box_tests += s.box_tests, total.contacts += s.collisions;
    total.area_computations += s.area_refreshes;
  }
  set_counters(state, total, allocations, times);
}
BENCHMARK(BM_LegacyStep)->ArgName("objects")->Arg(10'000)->Iterations(kFrames10k)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_LegacyStep)->ArgName("objects")->Arg(100'000)->Iterations(kFrames100k)->Unit(benchmark::kMicrosecond);

// ---- queries: the WorldTree (after) against the scan over every object (before) ----

// The BM_Detect world after one detect() (the WorldTree holds every object,
// depths from the screen policy), and 256 fixed queries inside it: rays from
// random points in random directions (nearest hit, unbounded), and boxes two
// lattice spacings wide. Arg "scan": 1 = ray_cast_scan / overlap_box_scan.
struct QueryWorld {
  Scene scene;
  std::unique_ptr<CollisionWorld> world;
  std::vector<Eigen::Vector3d> origins, dirs;
  std::vector<Aabb> boxes;
  explicit QueryWorld(int n) : scene(make_scene(n)) {
    world = std::make_unique<CollisionWorld>(collision_settings(scene, LodPolicy::screen));
    for (const ObjectDesc& o : scene.objects) (void)world->create(TreeSource::fixed(o.tree), o.pose);
    std::vector<Contact> contacts;
    world->detect(contacts);
    const Aabb& b = scene.settings.bounds;
    std::mt19937 rng(9);
    for (int i = 0; i < 256; ++i) {
      const Eigen::Vector3d u(unit(rng), unit(rng), unit(rng));
      const Eigen::Vector3d p = b.min + u.cwiseProduct(b.max - b.min);
      origins.push_back(p);
      dirs.push_back(Eigen::Vector3d(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5).normalized());
      boxes.push_back({p.array() - kSpacing, p.array() + kSpacing});
    }
  }
};

void BM_RayCast(benchmark::State& state) {
  QueryWorld q(int(state.range(0)));
  const bool scan = state.range(1) != 0;
  size_t k = 0;
  uint64_t hits = 0, allocations = 0;
  for (size_t i = 0; i < q.origins.size(); ++i) (void)q.world->ray_cast(q.origins[i], q.dirs[i], INFINITY);  // depths
  for (auto _ : state) {
    const uint64_t before = g_allocations.load();
    const auto hit = scan ? q.world->ray_cast_scan(q.origins[k], q.dirs[k], INFINITY)
                          : q.world->ray_cast(q.origins[k], q.dirs[k], INFINITY);
    allocations += g_allocations.load() - before;
    hits += hit.ok() && hit->has_value();
    k = (k + 1) % q.origins.size();
  }
  state.counters["hit_rate"] = double(hits) / double(state.iterations());
  state.counters["allocs_per_query"] = double(allocations) / double(state.iterations());
}
BENCHMARK(BM_RayCast)
    ->ArgsProduct({{10'000, 100'000}, {1, 0}})
    ->ArgNames({"objects", "scan"})
    ->Unit(benchmark::kMicrosecond);

void BM_OverlapBox(benchmark::State& state) {
  QueryWorld q(int(state.range(0)));
  const bool scan = state.range(1) != 0;
  std::vector<ObjectHandle> out;
  out.reserve(1024);
  size_t k = 0;
  uint64_t found = 0, allocations = 0;
  for (const Aabb& b : q.boxes) (void)q.world->overlap_box(b, out);  // depths and scratch
  for (auto _ : state) {
    const uint64_t before = g_allocations.load();
    (void)(scan ? q.world->overlap_box_scan(q.boxes[k], out) : q.world->overlap_box(q.boxes[k], out));
    allocations += g_allocations.load() - before;
    found += out.size();
    k = (k + 1) % q.boxes.size();
  }
  state.counters["found"] = double(found) / double(state.iterations());
  state.counters["allocs_per_query"] = double(allocations) / double(state.iterations());
}
BENCHMARK(BM_OverlapBox)
    ->ArgsProduct({{10'000, 100'000}, {1, 0}})
    ->ArgNames({"objects", "scan"})
    ->Unit(benchmark::kMicrosecond);

// One job on the built-in pool: `chunks` chunks of 2 µs of busy work, after
// a pause of `gap_us` (1000: the worker has gone to sleep; 0: it is still
// spinning from the job before). threads:1 is the serial time. Shows what a
// fork costs, with the worker awake and when it must be woken: why small
// worlds keep their pair scan and cell moves on the calling thread.
void BM_PoolJob(benchmark::State& state) {
  ThreadPool pool(int(state.range(0)));
  const auto gap = std::chrono::microseconds(state.range(1));
  const size_t chunks = size_t(state.range(2));
  const RangeTask work{[](const void*, size_t b, size_t e) {
                         const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(2 * (e - b));
                         while (std::chrono::steady_clock::now() < until) {
                         }
                       },
                       nullptr};
  FrameTimes times(state);
  for (auto _ : state) {
    if (gap.count() > 0) std::this_thread::sleep_for(gap);
    times.start();
    pool.parallel_for(chunks, 1, work);
    state.SetIterationTime(times.stop() * 1e-6);
  }
  state.counters["job_median_us"] = times.median();
}
BENCHMARK(BM_PoolJob)
    ->ArgsProduct({{1, 2}, {0, 1000}, {2, 3, 4, 8}})
    ->ArgNames({"threads", "gap_us", "chunks"})
    ->UseManualTime()
    ->Iterations(2000)
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace octbake

// --kernel=portable|avx2|avx512: the box-test kernel build to measure
// (kernel_option.h).
int main(int argc, char** argv) { return octbake::run_benchmarks(argc, argv, "bench_world"); }
