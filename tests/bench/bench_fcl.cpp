// octbake against FCL, the library a user would otherwise pick, in one run:
//  (a) per frame: CollisionWorld set_pose + set_camera + detect (fixed max
//      depth, screen LOD at 1 px) against FCL's DynamicAABBTree broadphase
//      (setTransform + update) + exact OBBRSS BVH mesh test, both fed the same
//      precomputed poses, with octbake's recall and precision against that
//      exact answer; and "paired": the same three run back to back in a
//      rotating order, octbake over FCL per repetition, so that a busy spell
//      of a shared host slows both sides of a ratio;
//  (b) per frame over the same candidate pairs (world boxes overlap):
//      octbake collide() at depth D against FCL OcTree-OcTree collision of
//      octomaps holding the same leaf boxes at depth D, precision of both;
//  (c) start-up: ModelLibrary loading the baked trees against building FCL
//      BVHs from the (already imported) meshes.
// Ratios are printed at the end from the best repetition of each case, the
// paired ones as a median and range over the repetitions.
//
// Build with -DOCTBAKE_BENCH=ON, then from the source root:
//   build/tests/bench_fcl --benchmark_repetitions=3 [--scene=PATH ...] [--meshes=DIR] [--frames=N] [--csv=FILE]
//     [--kernel=portable|avx2|avx512] (kernel_option.h)
// Default scenes: assets/scenes/test1.json and test2.json (the thesis's), and
// scales.json (sizes 536x apart), flythrough.json (all rotated, half
// spinning, camera on a path) and clutter.json (most statics resting on
// statics: pairs that never change), meshes in assets/;
// if they are missing, a generated scene of spheres, tori and slabs.
#include <benchmark/benchmark.h>
#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/geometry/octree/octree.h>
#include <fcl/narrowphase/collision.h>
#include <octomap/OcTree.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <numbers>
#include <random>
#include <set>

#include "bake.h"
#include "import.h"
#include "exact.h"
#include "gen.h"
#include "kernel_option.h"
#include "octbake/collide.h"
#include "octbake/collision_world.h"
#include "octbake/motion.h"
#include "run.h"

namespace octbake::scene {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// ---- inputs ----

struct BenchScene {
  std::string label;
  Scene scene;
  std::string meshes_dir;
  SceneModels models;
  int depth = 0;  // deepest baked depth: "fixed max" and the octree comparison depth
  ExactMeshes meshes;
  std::vector<std::string> mesh_paths;
  std::vector<Aabb> local_bounds;
  std::vector<int> mesh_of_object;
  std::vector<std::vector<Pose>> poses;  // per frame (--response none: no LOD changes them)
  std::vector<PairList> candidates;      // per frame: world boxes overlap
  std::vector<PairList> exact;           // per frame: FCL exact contacts
};

struct Score {
  uint64_t tp = 0, fp = 0, fn = 0;
  double precision() const { return tp + fp == 0 ? 1.0 : double(tp) / double(tp + fp); }
  double recall() const { return tp + fn == 0 ? 1.0 : double(tp) / double(tp + fn); }
  void add(const PairList& reported, const PairList& truth) {
    size_t t = 0;
    for (const auto& p : reported) {
      for (; t < truth.size() && truth[t] < p; ++t) ++fn;
      if (t < truth.size() && truth[t] == p) ++tp, ++t;
      else ++fp;
    }
    fn += truth.size() - t;
  }
};

std::vector<std::unique_ptr<BenchScene>> g_scenes;
std::map<std::string, Score> g_scores;  // benchmark name -> accuracy against the exact answer

// Fallback when the thesis scenes are absent: three shapes, baked to depth 6.
std::string generated_scene(const fs::path& dir) {
  fs::create_directories(dir / "meshes");
  auto write = [&](const std::string& name, const std::vector<Eigen::Vector3d>& v,
                   const std::vector<std::array<uint32_t, 3>>& f) {
    std::ofstream out(dir / "meshes" / (name + ".obj"));
    out.precision(17);
    for (const auto& p : v) out << "v " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
    for (const auto& t : f) out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  };
  {  // sphere, radius 1.5
    std::vector<Eigen::Vector3d> v;
    std::vector<std::array<uint32_t, 3>> f;
    const int seg = 32, rings = 16;
    for (int r = 0; r <= rings; ++r) {
      for (int s = 0; s < seg; ++s) {
        const double phi = std::numbers::pi * r / rings, th = 2 * std::numbers::pi * s / seg;
        v.emplace_back(1.5 * std::sin(phi) * std::cos(th), 1.5 * std::cos(phi), 1.5 * std::sin(phi) * std::sin(th));
      }
    }
    for (uint32_t r = 0; r < rings; ++r) {
      for (uint32_t s = 0; s < seg; ++s) {
        const uint32_t a = r * seg + s, b = r * seg + (s + 1) % seg;
        f.push_back({a, a + seg, b}), f.push_back({b, a + seg, b + seg});
      }
    }
    write("sphere", v, f);
  }
  {  // torus 2 / 0.5
    std::vector<Eigen::Vector3d> v;
    std::vector<std::array<uint32_t, 3>> f;
    const int seg = 48, sides = 16;
    for (int s = 0; s < seg; ++s) {
      for (int k = 0; k < sides; ++k) {
        const double u = 2 * std::numbers::pi * s / seg, w = 2 * std::numbers::pi * k / sides;
        v.emplace_back((2 + 0.5 * std::cos(w)) * std::cos(u), 0.5 * std::sin(w), (2 + 0.5 * std::cos(w)) * std::sin(u));
      }
    }
    for (uint32_t s = 0; s < seg; ++s) {
      for (uint32_t k = 0; k < sides; ++k) {
        const uint32_t a = s * sides + k, b = s * sides + (k + 1) % sides;
        const uint32_t c = ((s + 1) % seg) * sides + k, d = ((s + 1) % seg) * sides + (k + 1) % sides;
        f.push_back({a, c, b}), f.push_back({b, c, d});
      }
    }
    write("torus", v, f);
  }
  {  // slab 4 x 0.4 x 2
    std::vector<Eigen::Vector3d> v;
    for (int j = 0; j < 8; ++j) v.emplace_back((j & 1) ? 2 : -2, (j & 2) ? 0.2 : -0.2, (j & 4) ? 1 : -1);
    write("slab", v,
          {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
           {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}});
  }
  BakeConfig bake;
  for (const char* n : {"sphere", "torus", "slab"}) bake.inputs.push_back((dir / "meshes" / (std::string(n) + ".obj")).string());
  bake.out_dir = (dir / "baked").string();
  bake.options.depth = 6;
  if (run_bake(bake, stderr).failed != 0) return {};
  auto library = ModelLibrary::open(bake.out_dir);
  if (!library) return {};
  GenOptions gen;
  gen.static_count = 40, gen.moving_count = 40, gen.seed = 7;
  gen.models = {"sphere", "torus", "slab"};
  gen.world_size = 40, gen.speed = 6, gen.world_depth = 3;
  auto scene = generate_scene(gen, *library);
  if (!scene) return {};
  scene->camera.position = {0, 15, -45};
  const fs::path path = dir / "generated.json";
  std::ofstream(path) << write_scene(*scene, "baked");
  return path.string();
}

bool prepare(BenchScene& b, const std::string& path, const std::string& meshes_dir, int64_t frames) {
  auto scene = load_scene(path);
  if (!scene) return std::fprintf(stderr, "bench_fcl: %s: %s\n", path.c_str(), scene.error().message.c_str()), false;
  b.label = fs::path(path).stem().string();
  b.scene = std::move(*scene);
  b.scene.frames = std::min<int64_t>(b.scene.frames, frames);
  b.meshes_dir = meshes_dir;
  auto library = ModelLibrary::open(b.scene.baked);
  if (!library) return std::fprintf(stderr, "bench_fcl: %s\n", library.error().message.c_str()), false;
  auto models = load_scene_models(b.scene, *library, /*depth=*/12);
  if (!models) return std::fprintf(stderr, "bench_fcl: %s\n", models.error().message.c_str()), false;
  b.models = std::move(*models);
  for (const ObjectTree& t : b.models.trees) b.depth = std::max(b.depth, t.loaded_depth());
  for (const std::string& name : b.models.names) {
    const std::string mesh_path = find_mesh(meshes_dir, name);
    auto mesh = mesh_path.empty() ? Result<Mesh>(Error{ErrorCode::not_found, "no mesh"}) : import_mesh(mesh_path);
    if (!mesh) return std::fprintf(stderr, "bench_fcl: mesh for %s in %s: %s\n", name.c_str(), meshes_dir.c_str(),
                                   mesh.error().message.c_str()), false;
    b.mesh_paths.push_back(mesh_path);
    b.local_bounds.push_back(mesh_bounds(*mesh));
    b.meshes.add(std::move(*mesh));
  }
  for (uint32_t m : b.models.tree_of_object) b.mesh_of_object.push_back(static_cast<int>(m));
  // Poses of every frame under --response none, and the exact answer.
  RunOptions run;
  run.lod = {LodPolicy::fixed, 1, 1, 1.0};
  run.response = Response::none;
  run.report_poses = true;
  auto result = run_scene(b.scene, b.models, run, [&](const FrameReport& f) {
    b.poses.emplace_back(f.poses.begin(), f.poses.end());
    b.candidates.push_back(overlapping_bounds(f.poses, b.mesh_of_object, b.local_bounds));
    b.exact.push_back(exact_frame(f.poses, b.mesh_of_object, b.local_bounds, b.meshes).contacts);
  });
  if (!result) return std::fprintf(stderr, "bench_fcl: %s\n", result.error().message.c_str()), false;
  uint64_t contacts = 0, candidates = 0;
  for (size_t f = 0; f < b.exact.size(); ++f) contacts += b.exact[f].size(), candidates += b.candidates[f].size();
  std::fprintf(stderr, "bench_fcl: %s: %zu objects, %zu frames, depth %d, %.1f candidate pairs and %.2f contacts a frame\n",
               b.label.c_str(), b.scene.objects.size(), b.poses.size(), b.depth,
               double(candidates) / b.poses.size(), double(contacts) / b.poses.size());
  return true;
}

// ---- (a) per frame ----

// The objects with scripted motion (spinning ones move too): the ones whose
// poses both sides set each frame.
std::vector<uint32_t> moving_objects(const BenchScene& b) {
  std::vector<uint32_t> moving;
  for (size_t i = 0; i < b.scene.objects.size(); ++i) {
    const SceneObject& o = b.scene.objects[i];
    if (o.velocity.squaredNorm() > 0 || o.angular_velocity.squaredNorm() > 0) moving.push_back(static_cast<uint32_t>(i));
  }
  return moving;
}

// The world an engine links, driven as FCL is below: the same precomputed
// poses set on the moving objects, the camera of the frame, detect(). Areas on
// demand (only objects in candidate pairs), one thread.
class OctbakeFrames {
 public:
  OctbakeFrames(const BenchScene& b, LodSettings lod) : b_(b), moving_(moving_objects(b)) {
    settings_.bounds = b.scene.world;
    settings_.world_depth = b.scene.world_depth;
    settings_.lod = lod;
    settings_.camera = camera_on_path(b.scene.camera, b.scene.camera_path, 0);
  }

  // Every frame of the scene in a new world (its set-up not timed): seconds
  // per frame; counts and the score of the first pass.
  double pass() {
    CollisionWorld world(settings_);
    std::vector<ObjectHandle> handles;
    for (size_t i = 0; i < b_.scene.objects.size(); ++i)
      handles.push_back(*world.create(TreeSource::fixed(&b_.models.trees[b_.models.tree_of_object[i]]), b_.poses[0][i]));
    double seconds = 0;
    box_tests_ = areas_ = 0;
    for (size_t f = 0; f < b_.poses.size(); ++f) {
      const auto t0 = Clock::now();
      world.set_camera(camera_on_path(b_.scene.camera, b_.scene.camera_path, static_cast<int64_t>(f)));
      for (uint32_t i : moving_) (void)world.set_pose(handles[i], b_.poses[f][i]);
      const DetectStats d = world.detect(contacts_);
      box_tests_ += d.box_tests;
      areas_ += d.area_computations;
      seconds += seconds_since(t0);
      if (scored_) continue;
      PairList reported;
      for (const Contact& c : contacts_) reported.emplace_back(c.a.slot, c.b.slot);
      score_.add(reported, b_.exact[f]);
    }
    scored_ = true;
    return seconds / double(b_.poses.size());
  }

  double box_tests_per_frame() const { return double(box_tests_) / double(b_.poses.size()); }
  double areas_per_frame() const { return double(areas_) / double(b_.poses.size()); }
  const Score& score() const { return score_; }

 private:
  const BenchScene& b_;
  const std::vector<uint32_t> moving_;
  CollisionSettings settings_;
  std::vector<Contact> contacts_;
  uint64_t box_tests_ = 0, areas_ = 0;
  Score score_;
  bool scored_ = false;
};

void octbake_frames(benchmark::State& state, BenchScene* b, LodSettings lod, const std::string& name) {
  OctbakeFrames frames(*b, lod);
  for (auto _ : state) {
    state.SetIterationTime(frames.pass());
    state.counters["box_tests"] = frames.box_tests_per_frame();
    state.counters["areas"] = frames.areas_per_frame();
  }
  state.counters["recall"] = frames.score().recall();
  state.counters["precision"] = frames.score().precision();
  g_scores[name] = frames.score();
}

// The simulation layer (World::step through run_scene, --response none), as
// bench_fcl measured before 0.2: its time includes the scripted motion and
// the layer's area refreshes (every object's, whenever the camera moves),
// which the FCL side does not do. Kept for comparison.
void world_layer_frames(benchmark::State& state, BenchScene* b, LodSettings lod, const std::string& name) {
  RunOptions run;
  run.lod = lod;
  run.response = Response::none;
  Score score;
  bool scored = false;
  for (auto _ : state) {
    double step_seconds = 0;
    auto result = run_scene(b->scene, b->models, run, [&](const FrameReport& f) {
      step_seconds += f.ms / 1000;
      if (scored) return;
      PairList reported;
      for (const Collision& c : f.collisions) reported.emplace_back(c.a, c.b);
      score.add(reported, b->exact[f.frame]);
    });
    if (!result) return state.SkipWithError(result.error().message.c_str());
    scored = true;
    state.counters["box_tests"] = double(result->box_tests) / double(result->frames);
    state.SetIterationTime(step_seconds / double(result->frames));
  }
  state.counters["recall"] = score.recall();
  state.counters["precision"] = score.precision();
  g_scores[name] = score;
}

struct FclWorld {
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> objects;
  std::map<const fcl::CollisionObjectd*, uint32_t> index;
  fcl::DynamicAABBTreeCollisionManagerd manager;
};

struct FclPairs {
  const FclWorld* world;
  PairList hits;
};

bool exact_callback(fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2, void* data) {
  auto* pairs = static_cast<FclPairs*>(data);
  const fcl::CollisionRequestd request(/*num_max_contacts=*/1, /*enable_contact=*/false);
  fcl::CollisionResultd result;
  fcl::collide(o1, o2, request, result);
  if (result.isCollision()) {
    const uint32_t a = pairs->world->index.at(o1), b = pairs->world->index.at(o2);
    pairs->hits.emplace_back(std::min(a, b), std::max(a, b));
  }
  return false;  // keep going: every pair
}

// FCL's DynamicAABBTree over one CollisionObject per instance (sharing the
// BVH of its (mesh, scale)), driven as octbake is above.
class FclFrames {
 public:
  explicit FclFrames(const BenchScene& b) : b_(b), moving_(moving_objects(b)) {
    std::map<std::pair<int, double>, std::shared_ptr<fcl::CollisionGeometryd>> by_key;
    for (size_t i = 0; i < b.scene.objects.size(); ++i) {
      const Pose& p = b.poses[0][i];
      auto& g = by_key[{b.mesh_of_object[i], p.scale}];
      if (!g) g = build_bvh(b.meshes.mesh(b.mesh_of_object[i]), p.scale);
      w_.objects.push_back(std::make_unique<fcl::CollisionObjectd>(g, to_fcl(p)));
      w_.index[w_.objects.back().get()] = static_cast<uint32_t>(i);
    }
    std::vector<fcl::CollisionObjectd*> raw;
    for (auto& o : w_.objects) raw.push_back(o.get());
    w_.manager.registerObjects(raw);
    w_.manager.setup();
  }

  // Every frame of the scene: seconds per frame; the score of the first pass.
  double pass() {
    double seconds = 0;
    for (size_t f = 0; f < b_.poses.size(); ++f) {
      FclPairs pairs{&w_, {}};
      const auto t0 = Clock::now();
      for (uint32_t i : moving_) {
        w_.objects[i]->setTransform(to_fcl(b_.poses[f][i]));
        w_.objects[i]->computeAABB();
      }
      w_.manager.update();
      w_.manager.collide(&pairs, exact_callback);
      seconds += seconds_since(t0);
      if (!scored_) {
        std::sort(pairs.hits.begin(), pairs.hits.end());
        score_.add(pairs.hits, b_.exact[f]);
      }
    }
    scored_ = true;
    return seconds / double(b_.poses.size());
  }

  const Score& score() const { return score_; }

 private:
  const BenchScene& b_;
  const std::vector<uint32_t> moving_;
  FclWorld w_;
  Score score_;
  bool scored_ = false;
};

void fcl_frames(benchmark::State& state, BenchScene* b) {
  FclFrames frames(*b);
  for (auto _ : state) state.SetIterationTime(frames.pass());
  // FCL's broadphase + exact test is the reference: recall and precision show
  // that it agrees with the sweep-and-prune exact answer.
  state.counters["recall"] = frames.score().recall();
  state.counters["precision"] = frames.score().precision();
}

// The ratios the targets are stated in, octbake's frame over FCL's, with both
// sides measured back to back: each iteration runs every frame of the scene
// with octbake at fixed depth, at screen 1 px and with FCL, in a rotating
// order, so that a busy spell on a shared host slows all three alike rather
// than one case of the separate ones above. Counters: the ratios of the best
// passes of the repetition.
void paired_frames(benchmark::State& state, BenchScene* b, LodSettings fixed, LodSettings screen) {
  OctbakeFrames octbake_fixed(*b, fixed), octbake_screen(*b, screen);
  FclFrames fcl(*b);
  double best[3] = {INFINITY, INFINITY, INFINITY};
  int turn = 0;
  for (auto _ : state) {
    double total = 0;
    for (int k = 0; k < 3; ++k) {
      const int c = (turn + k) % 3;
      const double t = c == 0 ? octbake_fixed.pass() : c == 1 ? octbake_screen.pass() : fcl.pass();
      best[c] = std::min(best[c], t);
      total += t;
    }
    ++turn;
    state.SetIterationTime(total);
  }
  state.counters["fixed_over_fcl"] = best[0] / best[2];
  state.counters["screen_over_fcl"] = best[1] / best[2];
}

// ---- (b) octree against octree at equal depth ----

// The FCL side of one (model, scale): octomap voxels of side = the largest
// leaf extent (octomap voxels are cubes), every voxel that overlaps an
// occupied leaf box set, in a frame shifted so the tree's box starts at 0.
struct FclOctree {
  std::shared_ptr<fcl::OcTreed> tree;
  Eigen::Vector3d offset;  // local position of the octomap origin (scaled)
};

FclOctree build_fcl_octree(const ObjectTree& t, int depth, double scale) {
  const OctreeMasks& m = t.masks();
  const Eigen::Vector3d extent = scale * (m.bounds.max - m.bounds.min);
  const Eigen::Vector3d leaf = extent / double(1 << depth);
  const double r = leaf.maxCoeff();
  auto map = std::make_shared<octomap::OcTree>(r);
  for (const BoxCoord& c : m.boxes(depth)) {
    const Eigen::Vector3d lo = leaf.cwiseProduct(Eigen::Vector3d(c.x, c.y, c.z));
    const Eigen::Vector3d hi = lo + leaf;
    // Voxel i covers [i r, (i + 1) r); a closed leaf box touches voxels
    // floor(lo / r) .. floor(hi / r) (minus one when hi sits on a boundary).
    Eigen::Vector3i v0, v1;
    for (int k = 0; k < 3; ++k) {
      v0[k] = static_cast<int>(std::floor(lo[k] / r + 1e-9));
      v1[k] = std::max(v0[k], static_cast<int>(std::ceil(hi[k] / r - 1e-9)) - 1);
    }
    for (int x = v0.x(); x <= v1.x(); ++x)
      for (int y = v0.y(); y <= v1.y(); ++y)
        for (int z = v0.z(); z <= v1.z(); ++z)
          map->updateNode(octomap::point3d(float((x + 0.5) * r), float((y + 0.5) * r), float((z + 0.5) * r)), true,
                          /*lazy_eval=*/true);
  }
  map->updateInnerOccupancy();
  return {std::make_shared<fcl::OcTreed>(map), scale * m.bounds.min};
}

void octbake_pairs(benchmark::State& state, BenchScene* b, int depth, const std::string& name) {
  Score score;
  bool scored = false;
  for (auto _ : state) {
    uint64_t box_tests = 0;
    const auto t0 = Clock::now();
    std::vector<PairList> hits(b->poses.size());
    for (size_t f = 0; f < b->poses.size(); ++f) {
      for (const auto& [i, j] : b->candidates[f]) {
        const PlacedTree pa{&b->models.trees[b->models.tree_of_object[i]], b->poses[f][i], depth};
        const PlacedTree pb{&b->models.trees[b->models.tree_of_object[j]], b->poses[f][j], depth};
        const PairTest t = collide(pa, pb);
        box_tests += t.box_tests;
        if (t.hit) hits[f].emplace_back(i, j);
      }
    }
    state.SetIterationTime(seconds_since(t0) / double(b->poses.size()));
    state.counters["box_tests"] = double(box_tests) / double(b->poses.size());
    if (!scored) {
      for (size_t f = 0; f < hits.size(); ++f) score.add(hits[f], b->exact[f]);
      scored = true;
    }
  }
  state.counters["recall"] = score.recall();
  state.counters["precision"] = score.precision();
  g_scores[name] = score;
}

void fcl_octree_pairs(benchmark::State& state, BenchScene* b, int depth, const std::string& name) {
  std::map<std::pair<uint32_t, double>, FclOctree> trees;
  std::vector<const FclOctree*> of_object;
  for (size_t i = 0; i < b->scene.objects.size(); ++i) {
    const uint32_t t = b->models.tree_of_object[i];
    const double s = b->poses[0][i].scale;
    auto& slot = trees[{t, s}];
    if (!slot.tree) slot = build_fcl_octree(b->models.trees[t], depth, s);
    of_object.push_back(&slot);
  }
  auto transform = [&](size_t f, uint32_t i) {
    Pose p = b->poses[f][i];
    p.position += p.rotation * of_object[i]->offset;
    return to_fcl(p);
  };
  const fcl::CollisionRequestd request(/*num_max_contacts=*/1, /*enable_contact=*/false);
  Score score;
  bool scored = false;
  for (auto _ : state) {
    std::vector<PairList> hits(b->poses.size());
    const auto t0 = Clock::now();
    for (size_t f = 0; f < b->poses.size(); ++f) {
      for (const auto& [i, j] : b->candidates[f]) {
        fcl::CollisionResultd result;
        fcl::collide(of_object[i]->tree.get(), transform(f, i), of_object[j]->tree.get(), transform(f, j), request,
                     result);
        if (result.isCollision()) hits[f].emplace_back(i, j);
      }
    }
    state.SetIterationTime(seconds_since(t0) / double(b->poses.size()));
    if (!scored) {
      for (size_t f = 0; f < hits.size(); ++f) score.add(hits[f], b->exact[f]);
      scored = true;
    }
  }
  state.counters["recall"] = score.recall();
  state.counters["precision"] = score.precision();
  g_scores[name] = score;
}

// ---- (c) start-up ----

void octbake_startup(benchmark::State& state, BenchScene* b) {
  for (auto _ : state) {
    auto library = ModelLibrary::open(b->scene.baked);
    if (!library) return state.SkipWithError(library.error().message.c_str());
    auto models = load_scene_models(b->scene, *library, /*depth=*/12);
    if (!models) return state.SkipWithError(models.error().message.c_str());
    benchmark::DoNotOptimize(models->trees.data());
  }
}

void fcl_startup(benchmark::State& state, BenchScene* b) {
  // BVHs for every distinct (mesh, scale), from meshes already in memory:
  // reading the files is not counted, which favours FCL.
  std::set<std::pair<int, double>> keys;
  for (size_t i = 0; i < b->scene.objects.size(); ++i) keys.insert({b->mesh_of_object[i], b->poses[0][i].scale});
  for (auto _ : state) {
    for (const auto& [m, s] : keys) benchmark::DoNotOptimize(build_bvh(b->meshes.mesh(m), s).get());
  }
}

// ---- ratios from the best repetition of each case ----

class Collector : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      if (r.error_occurred) continue;
      const std::string& name = r.run_name.function_name;
      if (r.run_type == Run::RT_Iteration) {
        keep_best(name, r.GetAdjustedRealTime());  // in the benchmark's unit (us)
        for (const auto& [counter, value] : r.counters)
          if (counter.ends_with("_over_fcl")) ratios_[name + "/" + counter].push_back(value.value);
      } else {
        // With --benchmark_report_aggregates_only only these arrive: the
        // best time from "min", the ratios' median and range from "median",
        // "min" and "max" (used only where no repetition was seen).
        if (r.aggregate_name == "min") keep_best(name, r.GetAdjustedRealTime());
        for (const auto& [counter, value] : r.counters)
          if (counter.ends_with("_over_fcl")) aggregates_[name + "/" + counter][r.aggregate_name] = value.value;
      }
    }
    ConsoleReporter::ReportRuns(runs);
  }
  double best(const std::string& name) const {
    auto it = best_.find(name);
    return it == best_.end() ? NAN : it->second;
  }
  // A paired ratio over the repetitions: median, min and max (nan if not run).
  std::array<double, 3> ratio(const std::string& name) const {
    if (auto it = ratios_.find(name); it != ratios_.end()) {
      std::vector<double> v = it->second;
      std::sort(v.begin(), v.end());
      const size_t n = v.size();
      return {n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]), v.front(), v.back()};
    }
    const auto it = aggregates_.find(name);
    if (it == aggregates_.end()) return {NAN, NAN, NAN};
    const auto get = [&](const char* a) { return it->second.contains(a) ? it->second.at(a) : NAN; };
    return {get("median"), get("min"), get("max")};
  }

 private:
  void keep_best(const std::string& name, double t) {
    auto [it, fresh] = best_.try_emplace(name, t);
    if (!fresh) it->second = std::min(it->second, t);
  }

  std::map<std::string, double> best_;
  std::map<std::string, std::vector<double>> ratios_;                    // per repetition
  std::map<std::string, std::map<std::string, double>> aggregates_;     // by aggregate name
};

}  // namespace
}  // namespace octbake::scene

int main(int argc, char** argv) {
  using namespace octbake::scene;
  if (!octbake::take_kernel_option(argc, argv, "bench_fcl")) return 2;
  benchmark::Initialize(&argc, argv);
  std::vector<std::string> scene_paths;
  std::string meshes_dir, csv_path;
  int64_t frames = 300;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.rfind("--scene=", 0) == 0) scene_paths.push_back(a.substr(8));
    else if (a.rfind("--meshes=", 0) == 0) meshes_dir = a.substr(9);
    else if (a.rfind("--frames=", 0) == 0) frames = std::stoll(a.substr(9));
    else if (a.rfind("--csv=", 0) == 0) csv_path = a.substr(6);
    else return std::fprintf(stderr, "bench_fcl: unknown argument %s\n", a.c_str()), 2;
  }
  const fs::path source = OCTBAKE_SOURCE_DIR;
  if (scene_paths.empty()) {
    for (const char* s : {"assets/scenes/test1.json", "assets/scenes/test2.json", "assets/scenes/scales.json",
                          "assets/scenes/flythrough.json", "assets/scenes/clutter.json"}) {
      if (fs::exists(source / s)) scene_paths.push_back((source / s).string());
    }
    if (meshes_dir.empty()) meshes_dir = (source / "assets").string();
  }
  if (scene_paths.empty()) {
    const fs::path dir = fs::temp_directory_path() / ("octbake_bench_fcl_" + std::to_string(getpid()));
    const std::string generated = generated_scene(dir);
    if (generated.empty()) return std::fprintf(stderr, "bench_fcl: could not generate a scene\n"), 1;
    std::fprintf(stderr, "bench_fcl: assets/scenes/test1.json missing: using a generated scene in %s\n", dir.c_str());
    scene_paths.push_back(generated);
    meshes_dir = (dir / "meshes").string();
  }
  for (const std::string& p : scene_paths) {
    auto b = std::make_unique<BenchScene>();
    if (!prepare(*b, p, meshes_dir, frames)) return 1;
    g_scenes.push_back(std::move(b));
  }

  using octbake::LodPolicy;
  using octbake::LodSettings;
  for (auto& sp : g_scenes) {
    BenchScene* b = sp.get();
    const std::string s = b->label;
    // Each iteration runs every frame of the scene while the manual time is per
    // frame, so let Google Benchmark pick no iteration count from it.
    auto reg = [](const std::string& name, auto fn) {
      benchmark::RegisterBenchmark(name.c_str(), fn)
          ->UseManualTime()
          ->Iterations(3)
          ->Unit(benchmark::kMicrosecond)
          ->ComputeStatistics("min", [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); })
          ->ComputeStatistics("max", [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); });
    };
    const LodSettings fixed{LodPolicy::fixed, b->depth, b->depth, 1.0}, screen{LodPolicy::screen, 1, b->depth, 1.0};
    const std::string fixed_name = s + "/a_frame/octbake_fixed" + std::to_string(b->depth);
    const std::string screen_name = s + "/a_frame/octbake_screen1px";
    reg(fixed_name, [=](benchmark::State& st) { octbake_frames(st, b, fixed, fixed_name); });
    reg(screen_name, [=](benchmark::State& st) { octbake_frames(st, b, screen, screen_name); });
    reg(s + "/a_frame/fcl_broadphase_exact", [=](benchmark::State& st) { fcl_frames(st, b); });
    reg(s + "/a_frame/paired", [=](benchmark::State& st) { paired_frames(st, b, fixed, screen); });
    const std::string layer_name = s + "/a_frame/world_layer_fixed" + std::to_string(b->depth);
    reg(layer_name, [=](benchmark::State& st) { world_layer_frames(st, b, fixed, layer_name); });
    const std::string ob = s + "/b_octree/octbake_d" + std::to_string(b->depth);
    const std::string of = s + "/b_octree/fcl_octomap_d" + std::to_string(b->depth);
    reg(ob, [=](benchmark::State& st) { octbake_pairs(st, b, b->depth, ob); });
    reg(of, [=](benchmark::State& st) { fcl_octree_pairs(st, b, b->depth, of); });
    benchmark::RegisterBenchmark((s + "/c_startup/octbake_load").c_str(),
                                 [=](benchmark::State& st) { octbake_startup(st, b); })
        ->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark((s + "/c_startup/fcl_build_bvh").c_str(),
                                 [=](benchmark::State& st) { fcl_startup(st, b); })
        ->Unit(benchmark::kMicrosecond);
  }
  Collector collector;
  benchmark::RunSpecifiedBenchmarks(&collector);

  std::string csv = "scene,case,best_us,ratio_fcl_over_octbake,octbake_recall,octbake_precision,fcl_precision\n";
  std::printf("\nRatios (best repetition; > 1 means octbake is faster):\n");
  for (auto& sp : g_scenes) {
    const BenchScene& b = *sp;
    const std::string s = b.label, d = std::to_string(b.depth);
    const double fx = collector.best(s + "/a_frame/octbake_fixed" + d);
    const double sc = collector.best(s + "/a_frame/octbake_screen1px");
    const double fe = collector.best(s + "/a_frame/fcl_broadphase_exact");
    const double wl = collector.best(s + "/a_frame/world_layer_fixed" + d);
    const double ob = collector.best(s + "/b_octree/octbake_d" + d), of = collector.best(s + "/b_octree/fcl_octomap_d" + d);
    const double lo = collector.best(s + "/c_startup/octbake_load"), bv = collector.best(s + "/c_startup/fcl_build_bvh");
    const Score& sf = g_scores[s + "/a_frame/octbake_fixed" + d];
    const Score& ss = g_scores[s + "/a_frame/octbake_screen1px"];
    const Score& so = g_scores[s + "/b_octree/octbake_d" + d];
    const Score& sq = g_scores[s + "/b_octree/fcl_octomap_d" + d];
    const auto pf = collector.ratio(s + "/a_frame/paired/fixed_over_fcl");
    const auto ps = collector.ratio(s + "/a_frame/paired/screen_over_fcl");
    // A line for each comparison whose cases ran (--benchmark_filter may leave some out).
    const auto ran = [](std::initializer_list<double> v) {
      return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
    };
    if (ran({fe, fx, sc}))
      std::printf("%s: (a) FCL exact %.1f us/frame; octbake fixed %s %.1f us (%.2fx, recall %.4f, precision %.4f); "
                  "screen 1px %.1f us (%.2fx, recall %.4f, precision %.4f)\n",
                  s.c_str(), fe, d.c_str(), fx, fe / fx, sf.recall(), sf.precision(), sc, fe / sc, ss.recall(),
                  ss.precision());
    if (ran({pf[0], ps[0]}))
      std::printf("%s: (a) paired, octbake's frame over FCL's (the three run back to back; median and range over the "
                  "repetitions): fixed %s %.3fx (%.3f-%.3f), screen 1px %.3fx (%.3f-%.3f)\n",
                  s.c_str(), d.c_str(), pf[0], pf[1], pf[2], ps[0], ps[1], ps[2]);
    if (ran({fe, wl}))
      std::printf("%s: (a) the World layer at fixed %s (scripted motion and its area refreshes included): %.1f us (%.2fx)\n",
                  s.c_str(), d.c_str(), wl, fe / wl);
    if (ran({ob, of}))
      std::printf("%s: (b) depth %s over the same candidate pairs: octbake %.1f us/frame (precision %.4f, recall %.4f), "
                  "FCL octomap %.1f us/frame (precision %.4f, recall %.4f): %.2fx\n",
                  s.c_str(), d.c_str(), ob, so.precision(), so.recall(), of, sq.precision(), sq.recall(), of / ob);
    if (ran({lo, bv}))
      std::printf("%s: (c) start-up: octbake load %.1f us, FCL BVH build %.1f us: %.0fx\n", s.c_str(), lo, bv, bv / lo);
    char row[512];
    std::snprintf(row, sizeof row, "%s,a_fixed%s,%.3f,%.4f,%.6f,%.6f,1\n%s,a_screen1px,%.3f,%.4f,%.6f,%.6f,1\n"
                  "%s,a_fcl_exact,%.3f,1,,,1\n%s,b_octbake_d%s,%.3f,%.4f,%.6f,%.6f,%.6f\n%s,b_fcl_octomap_d%s,%.3f,1,,,%.6f\n"
                  "%s,c_octbake_load,%.3f,%.4f,,,\n%s,c_fcl_build_bvh,%.3f,1,,,\n",
                  s.c_str(), d.c_str(), fx, fe / fx, sf.recall(), sf.precision(), s.c_str(), sc, fe / sc, ss.recall(),
                  ss.precision(), s.c_str(), fe, s.c_str(), d.c_str(), ob, of / ob, so.recall(), so.precision(),
                  sq.precision(), s.c_str(), d.c_str(), of, sq.precision(), s.c_str(), lo, bv / lo, s.c_str(), bv);
    csv += row;
    std::snprintf(row, sizeof row, "%s,a_world_layer_fixed%s,%.3f,%.4f,,,1\n", s.c_str(), d.c_str(), wl, fe / wl);
    csv += row;
    // Paired: the median ratio over the repetitions (FCL over octbake, as the
    // other rows), no time of its own.
    std::snprintf(row, sizeof row, "%s,a_paired_fixed%s,,%.4f,,,1\n%s,a_paired_screen1px,,%.4f,,,1\n", s.c_str(),
                  d.c_str(), 1 / pf[0], s.c_str(), 1 / ps[0]);
    csv += row;
  }
  if (!csv_path.empty()) std::ofstream(csv_path) << csv;
  benchmark::Shutdown();
  return 0;
}
