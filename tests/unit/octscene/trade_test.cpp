// octscene trade: the exact mesh-mesh helper on hand-made cases and against an
// independent box-box oracle, then the whole trade on small random scenes.
#include <gtest/gtest.h>

#include <functional>
#include <stdlib.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>

#include "box_mesh.h"
#include "bake.h"
#include "exact.h"
#include "trade.h"

namespace octbake::scene {
namespace {

namespace fs = std::filesystem;

double unit(std::mt19937& rng) { return rng() / 4294967296.0; }  // [0, 1), no std distributions
double symmetric(std::mt19937& rng) { return 2 * unit(rng) - 1; }

Eigen::Quaterniond random_rotation(std::mt19937& rng) {
  Eigen::Vector4d v;
  do {
    v = {symmetric(rng), symmetric(rng), symmetric(rng), symmetric(rng)};
  } while (v.norm() < 0.1 || v.norm() > 1);
  v.normalize();
  return Eigen::Quaterniond(v[3], v[0], v[1], v[2]);
}

using testing::box_mesh;

Mesh unit_cube() { return box_mesh({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}); }

Mesh uv_sphere(double radius, int segments, int rings) {
  Mesh m;
  for (int r = 0; r <= rings; ++r) {
    const double phi = std::numbers::pi * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double theta = 2 * std::numbers::pi * s / segments;
      m.positions.emplace_back(radius * std::sin(phi) * std::cos(theta), radius * std::cos(phi),
                               radius * std::sin(phi) * std::sin(theta));
    }
  }
  for (int r = 0; r < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      const uint32_t a = r * segments + s, b = r * segments + (s + 1) % segments;
      const uint32_t c = a + segments, d = b + segments;
      m.triangles.push_back({a, c, b});
      m.triangles.push_back({b, c, d});
    }
  }
  return m;
}

Mesh torus(double big, double small, int segments, int sides) {
  Mesh m;
  for (int s = 0; s < segments; ++s) {
    const double u = 2 * std::numbers::pi * s / segments;
    for (int k = 0; k < sides; ++k) {
      const double v = 2 * std::numbers::pi * k / sides;
      m.positions.emplace_back((big + small * std::cos(v)) * std::cos(u), small * std::sin(v),
                               (big + small * std::cos(v)) * std::sin(u));
    }
  }
  for (int s = 0; s < segments; ++s) {
    for (int k = 0; k < sides; ++k) {
      const uint32_t a = s * sides + k, b = s * sides + (k + 1) % sides;
      const uint32_t c = ((s + 1) % segments) * sides + k, d = ((s + 1) % segments) * sides + (k + 1) % sides;
      m.triangles.push_back({a, c, b});
      m.triangles.push_back({b, c, d});
    }
  }
  return m;
}

void write_obj(const fs::path& path, const Mesh& mesh) {
  std::ofstream out(path);
  out.precision(17);
  for (const auto& p : mesh.positions) out << "v " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  for (const auto& t : mesh.triangles) out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
}

Pose at(const Eigen::Vector3d& p, const Eigen::Quaterniond& q = Eigen::Quaterniond::Identity(), double scale = 1) {
  Pose pose;
  pose.position = p;
  pose.rotation = q;
  pose.scale = scale;
  return pose;
}

// ---- the exact helper on hand-made cases ----

TEST(Exact, SeparatedAndOverlappingCubes) {
  ExactMeshes meshes;
  const int cube = meshes.add(unit_cube());
  EXPECT_FALSE(meshes.collide(cube, at({0, 0, 0}), cube, at({1.001, 0, 0})));
  EXPECT_FALSE(meshes.collide(cube, at({0, 0, 0}), cube, at({0, 1.001, 0.3})));
  EXPECT_TRUE(meshes.collide(cube, at({0, 0, 0}), cube, at({0.999, 0, 0})));
  EXPECT_TRUE(meshes.collide(cube, at({0, 0, 0}), cube, at({0.999, 0.999, 0.999})));
  // Diagonal neighbours sharing only a corner region, one axis apart.
  EXPECT_FALSE(meshes.collide(cube, at({0, 0, 0}), cube, at({0.999, 0.999, 1.001})));
}

TEST(Exact, TouchingFacesCountAsContact) {
  // Coplanar faces in contact: the surfaces share points, so this is a
  // contact, and octbake's padded boxes must report it too.
  ExactMeshes meshes;
  const int cube = meshes.add(unit_cube());
  EXPECT_TRUE(meshes.collide(cube, at({0, 0, 0}), cube, at({1.0, 0.25, 0.25})));
}

TEST(Exact, RotatedCubeCornerReach) {
  // B turned 45 degrees about z reaches sqrt(1/2) from its centre along x.
  ExactMeshes meshes;
  const int cube = meshes.add(unit_cube());
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(std::numbers::pi / 4, Eigen::Vector3d::UnitZ()));
  const double reach = 0.5 + std::sqrt(0.5);
  EXPECT_TRUE(meshes.collide(cube, at({0, 0, 0}), cube, at({reach - 0.01, 0, 0}, turn)));
  EXPECT_FALSE(meshes.collide(cube, at({0, 0, 0}), cube, at({reach + 0.01, 0, 0}, turn)));
  // The order of the pair does not matter.
  EXPECT_TRUE(meshes.collide(cube, at({reach - 0.01, 0, 0}, turn), cube, at({0, 0, 0})));
}

TEST(Exact, ScaleGetsItsOwnBvh) {
  ExactMeshes meshes;
  const int cube = meshes.add(unit_cube());
  // Scale 2 makes B [-1, 1]: faces meet A's at x = 0.5 when B sits at 1.5.
  EXPECT_TRUE(meshes.collide(cube, at({0, 0, 0}), cube, at({1.49, 0, 0}, Eigen::Quaterniond::Identity(), 2)));
  EXPECT_FALSE(meshes.collide(cube, at({0, 0, 0}), cube, at({1.51, 0, 0}, Eigen::Quaterniond::Identity(), 2)));
  EXPECT_EQ(meshes.bvh_count(), 2u);
}

TEST(Exact, FindMeshTriesExtensionsInOrder) {
  const fs::path dir = fs::temp_directory_path() / ("octbake_find_mesh_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  EXPECT_EQ(find_mesh(dir.string(), "thing"), "");
  std::ofstream(dir / "thing.stl") << "x";
  EXPECT_EQ(find_mesh(dir.string(), "thing"), (dir / "thing.stl").string());
  std::ofstream(dir / "thing.obj") << "x";
  EXPECT_EQ(find_mesh(dir.string(), "thing"), (dir / "thing.obj").string());
  fs::remove_all(dir);
}

// Separating axis test for two equal cubes (edge 1): the solids overlap
// exactly when the surfaces meet, since neither can hold the other.
// Returns the largest separation over the 15 axes (> 0: apart).
double cube_separation(const Pose& a, const Pose& b) {
  const Eigen::Matrix3d ra = a.rotation.toRotationMatrix(), rb = b.rotation.toRotationMatrix();
  const Eigen::Vector3d d = b.position - a.position;
  std::vector<Eigen::Vector3d> axes;
  for (int i = 0; i < 3; ++i) axes.push_back(ra.col(i)), axes.push_back(rb.col(i));
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const Eigen::Vector3d c = ra.col(i).cross(rb.col(j));
      if (c.norm() > 1e-9) axes.push_back(c.normalized());
    }
  }
  double worst = -1e300;
  for (const Eigen::Vector3d& n : axes) {
    double ra_r = 0, rb_r = 0;
    for (int i = 0; i < 3; ++i) ra_r += 0.5 * std::abs(ra.col(i).dot(n)), rb_r += 0.5 * std::abs(rb.col(i).dot(n));
    worst = std::max(worst, std::abs(d.dot(n)) - ra_r - rb_r);
  }
  return worst;
}

TEST(Exact, AgreesWithSeparatingAxisOracle) {
  std::mt19937 rng(20240611);
  ExactMeshes meshes;
  const int cube = meshes.add(unit_cube());
  int hits = 0, trials = 0;
  for (int k = 0; k < 2000; ++k) {
    const Pose a = at({0, 0, 0}, random_rotation(rng));
    const Pose b = at({1.6 * symmetric(rng), 1.6 * symmetric(rng), 1.6 * symmetric(rng)}, random_rotation(rng));
    const double sep = cube_separation(a, b);
    if (std::abs(sep) < 1e-6) continue;  // too close to call in floating point
    ++trials;
    const bool expected = sep < 0;
    hits += expected;
    ASSERT_EQ(meshes.collide(cube, a, cube, b), expected) << "trial " << k << " separation " << sep;
  }
  // Not vacuous: both answers occur often.
  EXPECT_GT(hits, trials * 3 / 10);
  EXPECT_LT(hits, trials * 7 / 10);
}

// ---- the trade on small scenes ----

class TradeScene : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("octbake_trade_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "meshes");
    write_obj(dir_ / "meshes" / "ball.obj", uv_sphere(1.2, 20, 12));
    write_obj(dir_ / "meshes" / "ring.obj", torus(1.4, 0.35, 24, 10));
    write_obj(dir_ / "meshes" / "slab.obj", box_mesh({-1.5, -0.2, -1}, {1.5, 0.2, 1}));
    BakeConfig bake;
    for (const char* name : {"ball", "ring", "slab"}) bake.inputs.push_back((dir_ / "meshes" / (std::string(name) + ".obj")).string());
    bake.out_dir = (dir_ / "baked").string();
    bake.options.depth = kDepth;
    const BakeSummary summary = run_bake(bake, stderr);
    ASSERT_EQ(summary.failed, 0);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Objects placed and moving at random in a small world, so pairs pass
  // through each other (--response none) in some frames.
  Scene random_scene(uint32_t seed, int objects, int64_t frames) const {
    std::mt19937 rng(seed);
    Scene s;
    s.baked = (dir_ / "baked").string();
    s.camera.position = {0, 4, -22};
    s.camera.look_at = {0, 0, 0};
    s.camera.viewport_w = 640, s.camera.viewport_h = 480;
    s.world = {{-6, -6, -6}, {6, 6, 6}};
    s.world_depth = 2;
    s.timestep = 1.0 / 30;
    s.frames = frames;
    const char* models[] = {"ball", "ring", "slab"};
    for (int i = 0; i < objects; ++i) {
      SceneObject o;
      o.name = "obj_" + std::to_string(i);
      o.model = models[rng() % 3];
      o.pose = at({3.5 * symmetric(rng), 3.5 * symmetric(rng), 3.5 * symmetric(rng)}, random_rotation(rng),
                  0.7 + 0.6 * unit(rng));
      o.velocity = {4 * symmetric(rng), 4 * symmetric(rng), 4 * symmetric(rng)};
      s.objects.push_back(o);
    }
    return s;
  }

  static constexpr int kDepth = 5;
  fs::path dir_;
};

TEST_F(TradeScene, RecallIsOneAndFinerIsNeverWorse) {
  uint64_t contacts = 0, coarse_false_positives = 0;
  for (uint32_t seed : {1u, 2u, 3u}) {
    const Scene scene = random_scene(seed, /*objects=*/7, /*frames=*/45);
    auto library = ModelLibrary::open(scene.baked);
    ASSERT_TRUE(library) << library.error().message;
    TradeOptions options;
    options.meshes = (dir_ / "meshes").string();
    auto report = run_trade(scene, *library, options);
    ASSERT_TRUE(report) << report.error().message;
    EXPECT_TRUE(report->warnings.empty()) << report->warnings.front();
    EXPECT_EQ(report->frames, 45);
    // fixed 1..5, thesis, screen at 5 tolerances.
    ASSERT_EQ(report->rows.size(), size_t(kDepth + 1 + 5));
    for (const TradeRow& row : report->rows) {
      EXPECT_EQ(row.false_negatives, 0u) << "seed " << seed << " " << row.label;
      EXPECT_EQ(row.recall(), 1.0) << row.label;
      EXPECT_EQ(row.true_positives, report->exact_contacts) << row.label;
    }
    for (const Miss& m : report->misses) {
      ADD_FAILURE() << "seed " << seed << " " << m.setting << " missed frame " << m.frame << " pair " << m.a << ","
                    << m.b << " depths " << m.depth_a << "," << m.depth_b;
    }
    const TradeRow& finest = report->rows[kDepth - 1];
    ASSERT_EQ(finest.label, "fixed " + std::to_string(kDepth));
    for (int d = 1; d < kDepth; ++d) {
      const TradeRow& coarse = report->rows[d - 1];
      EXPECT_LE(finest.false_positives, coarse.false_positives) << "seed " << seed << " depth " << d;
      // Deeper descents test at least as many boxes.
      EXPECT_LE(coarse.box_tests_per_frame, report->rows[d].box_tests_per_frame) << "seed " << seed << " depth " << d;
    }
    contacts += report->exact_contacts;
    coarse_false_positives += report->rows[0].false_positives;
  }
  // Not vacuous: real contacts happened, and depth 1 over-reported some.
  EXPECT_GT(contacts, 0u);
  EXPECT_GT(coarse_false_positives, 0u);
}

TEST_F(TradeScene, MissingMeshIsAnError) {
  const Scene scene = random_scene(4, /*objects=*/3, /*frames=*/2);
  auto library = ModelLibrary::open(scene.baked);
  ASSERT_TRUE(library);
  TradeOptions options;
  options.meshes = (dir_ / "nowhere").string();
  auto report = run_trade(scene, *library, options);
  ASSERT_FALSE(report);
  EXPECT_EQ(report.error().code, ErrorCode::not_found);
}

TEST_F(TradeScene, CoordinatesPastTheExactRangeAreAnError) {
  // FCL's squares overflow past ~1e154: it reported a contact that is not
  // there, which the score counted as octbake's miss. Refused instead; just
  // inside the limit the scene is scored, recall 1.
  auto library = ModelLibrary::open((dir_ / "baked").string());
  ASSERT_TRUE(library);
  TradeOptions options;
  options.meshes = (dir_ / "meshes").string();
  options.max_depth = 2;
  auto trade = [&](const std::function<void(Scene&)>& edit) {
    Scene scene = random_scene(5, /*objects=*/3, /*frames=*/2);
    edit(scene);
    return run_trade(scene, *library, options);
  };
  struct Case {
    std::function<void(Scene&)> edit;
    std::string reason;
  };
  const Case refused[] = {
      {[](Scene& s) { s.objects[1].pose.scale = 1e155; }, "object \"obj_1\" reaches 1.2e+155"},
      {[](Scene& s) { s.objects[2].pose.position.y() = -2e151; }, "object \"obj_2\" reaches 2e+151"},
      {[](Scene& s) { s.objects[0].velocity.x() = 1e152; }, "object \"obj_0\" reaches"},
      {[](Scene& s) { s.world.max.z() = 1e160; }, "world box reaches 1e+160"},
  };
  for (const Case& c : refused) {
    auto report = trade(c.edit);
    ASSERT_FALSE(report) << c.reason;
    EXPECT_EQ(report.error().code, ErrorCode::invalid_argument);
    EXPECT_EQ(report.error().message.rfind(c.reason, 0), 0u) << report.error().message;
    EXPECT_NE(report.error().message.find("the exact reference (FCL)"), std::string::npos) << report.error().message;
  }
  // Big but inside: an object scaled by 1e140 swallowing the others.
  auto inside = trade([](Scene& s) { s.objects[1].pose.scale = 1e140; });
  ASSERT_TRUE(inside) << inside.error().message;
  for (const TradeRow& row : inside->rows) EXPECT_EQ(row.false_negatives, 0u) << row.label;
  EXPECT_TRUE(inside->misses.empty());
}

}  // namespace
}  // namespace octbake::scene
