// collide() against an exact mesh-mesh test (FCL): over random poses of real
// meshes, at every depth pair, it never misses a contact, coarser depths never
// report less than finer ones, the argument order does not matter, and the
// scalar reference descent gives the same answer. Also at a 1e7 world offset,
// at scales 1e-4 and 1e4, for touching meshes, for objects 400x to 4000x
// apart in size, and for extreme aspect ratios (flat quads, needles, walls).
#include <fcl/fcl.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <numbers>
#include <random>

#include "build_tree.h"
#include "import.h"
#include "octbake/collide.h"

#include "seeded_random.h"

namespace octbake {
namespace {

constexpr int kDepth = 6;

// Debug and sanitizer builds run a tenth of the poses; OCTBAKE_ORACLE_SCALE
// multiplies the counts (e.g. 10 for a long soak).
int pose_count(int release_count) {
#if defined(__SANITIZE_ADDRESS__) || !defined(NDEBUG)
  release_count /= 10;
#endif
  if (const char* s = std::getenv("OCTBAKE_ORACLE_SCALE")) release_count = int(release_count * std::atof(s));
  return std::max(release_count, 1);
}

using test::random_rotation;
using test::uniform01;

struct Model {
  std::string name;
  Mesh mesh;
  ObjectTree tree;
  Eigen::Vector3d centre;  // of the local bounds
  double radius = 1;       // half the bounds diagonal
};

Mesh cube_mesh() {  // [0,1]^3, 12 triangles
  Mesh m;
  for (int k = 0; k < 8; ++k) m.positions.emplace_back(k & 1, (k >> 1) & 1, (k >> 2) & 1);
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

Mesh quad_mesh() {  // flat unit square in z = 0: a tree with a zero-thickness axis
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  m.triangles = {{0, 1, 2}, {1, 3, 2}};
  return m;
}

// An axis-aligned box mesh of the given size (a needle when long and thin).
Mesh box_mesh(const Eigen::Vector3d& size) {
  Mesh m = cube_mesh();
  for (auto& p : m.positions) p = p.cwiseProduct(size);
  return m;
}

Model make_model(std::string name, Mesh mesh) {
  Model m;
  m.name = std::move(name);
  OctreeMasks masks = build_tree(mesh, kDepth, Occupancy::surface);
  m.centre = 0.5 * (masks.bounds.min + masks.bounds.max);
  m.radius = 0.5 * (masks.bounds.max - masks.bounds.min).norm();
  TreeInfo info;
  info.name = m.name;
  info.bounds = masks.bounds;
  info.depth = kDepth;
  m.tree = ObjectTree(std::move(info), std::move(masks));
  m.mesh = std::move(mesh);
  return m;
}

// The bundled assets plus real models shipped with assimp, and two made here.
const std::vector<Model>& models() {
  static const std::vector<Model> all = [] {
    std::vector<std::string> paths;
    const std::filesystem::path assets = std::filesystem::path(OCTBAKE_SOURCE_DIR) / "assets";
    if (std::filesystem::is_directory(assets))
      for (const auto& e : std::filesystem::directory_iterator(assets))
        if (e.path().extension() == ".obj") paths.push_back(e.path().string());
    std::sort(paths.begin(), paths.end());
    paths.push_back("/usr/share/assimp/models/OBJ/spider.obj");
    paths.push_back("/usr/share/assimp/models/Collada/duck.dae");
    std::vector<Model> out;
    for (const auto& path : paths) {
      Result<Mesh> mesh = import_mesh(path);
      if (!mesh) {
        ADD_FAILURE() << path << ": " << mesh.error().message;
        continue;
      }
      out.push_back(make_model(std::filesystem::path(path).filename().string(), std::move(mesh).value()));
    }
    out.push_back(make_model("cube", cube_mesh()));
    out.push_back(make_model("quad", quad_mesh()));
    return out;
  }();
  return all;
}

// FCL has no scale: the vertices are scaled before the BVH is built.
std::shared_ptr<fcl::CollisionGeometryd> fcl_model(const Mesh& mesh, double scale) {
  auto bvh = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
  std::vector<fcl::Vector3d> points;
  for (const auto& p : mesh.positions) points.push_back(scale * p);
  std::vector<fcl::Triangle> tris;
  for (const auto& t : mesh.triangles) tris.emplace_back(t[0], t[1], t[2]);
  bvh->beginModel();
  bvh->addSubModel(points, tris);
  bvh->endModel();
  return bvh;
}

fcl::Transform3d to_fcl(const Pose& pose) {
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.linear() = pose.rotation.toRotationMatrix();
  tf.translation() = pose.position;
  return tf;
}

bool fcl_collide(const fcl::CollisionObjectd& a, const fcl::CollisionObjectd& b) {
  fcl::CollisionRequestd request;
  fcl::CollisionResultd result;
  fcl::collide(&a, &b, request, result);
  return result.isCollision();
}

struct Scenario {
  Eigen::Vector3d offset{0, 0, 0};
  double scale = 1;
  int poses = 0;
  uint32_t seed = 1;
};

// Hit grids for every depth pair in both orders: symmetric and monotone.
// Returns the finest pair's answer through `finest`.
void check_grids(const PlacedTree& a0, const PlacedTree& b0, bool exact, const std::string& what,
                 bool* finest = nullptr) {
  bool grid[kDepth + 1][kDepth + 1];
  PlacedTree a = a0, b = b0;
  for (int da = 0; da <= kDepth; ++da)
    for (int db = 0; db <= kDepth; ++db) {
      a.depth = da;
      b.depth = db;
      const PairTest ab = collide(a, b), ba = collide(b, a);
      grid[da][db] = ab.hit;
      ASSERT_EQ(ab.hit, ba.hit) << what << " depths " << da << "-" << db;
      ASSERT_EQ(ab.hit, collide_reference(a, b).hit) << "differs from the reference: " << what << " depths " << da
                                                      << "-" << db;
      ASSERT_TRUE(ab.hit || !exact) << "missed contact: " << what << " depths " << da << "-" << db;
      ASSERT_TRUE(!ab.hit || da == 0 || grid[da - 1][db]) << what << " not monotone at " << da << "-" << db;
      ASSERT_TRUE(!ab.hit || db == 0 || grid[da][db - 1]) << what << " not monotone at " << da << "-" << db;
    }
  if (finest) *finest = grid[kDepth][kDepth];
}

void run_scenario(const Scenario& sc) {
  const auto& ms = models();
  ASSERT_GE(ms.size(), 4u);
  std::vector<std::shared_ptr<fcl::CollisionGeometryd>> geometry;
  for (const Model& m : ms) geometry.push_back(fcl_model(m.mesh, sc.scale / m.radius));

  std::mt19937 rng(sc.seed);
  int exact_hits = 0, coarse_only = 0, pruned = 0;
  for (int k = 0; k < sc.poses; ++k) {
    const size_t ia = rng() % ms.size(), ib = rng() % ms.size();
    const Model &ma = ms[ia], &mb = ms[ib];
    // Bounds centres a random distance apart, each mesh normalised to radius `scale`.
    const Eigen::Vector3d dir = random_rotation(rng) * Eigen::Vector3d::UnitX();
    const double distance = 2.2 * uniform01(rng) * sc.scale;
    Pose pa, pb;
    pa.rotation = random_rotation(rng);
    pb.rotation = random_rotation(rng);
    pa.scale = sc.scale / ma.radius;
    pb.scale = sc.scale / mb.radius;
    pa.position = sc.offset - pa.rotation * (pa.scale * ma.centre);
    pb.position = sc.offset + distance * dir - pb.rotation * (pb.scale * mb.centre);

    const fcl::CollisionObjectd oa(geometry[ia], to_fcl(pa)), ob(geometry[ib], to_fcl(pb));
    const bool exact = fcl_collide(oa, ob);
    exact_hits += exact;
    const PlacedTree a{&ma.tree, pa, kDepth}, b{&mb.tree, pb, kDepth};
    const std::string what = "pose " + std::to_string(k) + " " + ma.name + " vs " + mb.name;
    bool finest = false;
    check_grids(a, b, exact, what, &finest);
    if (::testing::Test::HasFatalFailure()) return;
    const bool roots = collide({&ma.tree, pa, 0}, {&mb.tree, pb, 0}).hit;
    coarse_only += !exact && roots;
    pruned += roots && !finest;
  }
  std::printf("  %d poses: %d contacts (FCL), %d root overlaps without contact, %d of them rejected at 6-6\n",
              sc.poses, exact_hits, coarse_only, pruned);
  // Not vacuous: contacts and near misses are both common.
  EXPECT_GT(exact_hits, sc.poses * 3 / 10) << "of " << sc.poses;
  EXPECT_LT(exact_hits, sc.poses * 7 / 10) << "of " << sc.poses;
  EXPECT_GT(coarse_only, sc.poses / 20) << "roots overlap without contact";
  EXPECT_GT(pruned, coarse_only / 2) << "the trees reject most root-only overlaps";
}

TEST(Oracle, NeverMissesAContact) { run_scenario({{0, 0, 0}, 1.0, pose_count(3000), 11}); }
TEST(Oracle, FarFromTheOrigin) { run_scenario({{1e7, -1e7, 1e7}, 1.0, pose_count(1000), 12}); }
TEST(Oracle, TinyScale) { run_scenario({{0, 0, 0}, 1e-4, pose_count(1000), 13}); }
TEST(Oracle, HugeScale) { run_scenario({{0, 0, 0}, 1e4, pose_count(1000), 14}); }
TEST(Oracle, TinyScaleFarAway) { run_scenario({{1e7 * 1e-4, -1e3, 1e3}, 1e-4, pose_count(500), 15}); }

// B moved onto A along FCL's nearest points: the meshes touch.
TEST(Oracle, TouchingMeshesHitAtEveryDepth) {
  const auto& ms = models();
  std::mt19937 rng(21);
  const int poses = pose_count(100);
  for (const auto& [offset, scale] : {std::pair{Eigen::Vector3d(0, 0, 0), 1.0},
                                      std::pair{Eigen::Vector3d(1e7, -1e7, 1e7), 1.0},
                                      std::pair{Eigen::Vector3d(0, 0, 0), 1e-4},
                                      std::pair{Eigen::Vector3d(0, 0, 0), 1e4}}) {
    std::vector<std::shared_ptr<fcl::CollisionGeometryd>> geometry;
    for (const Model& m : ms) geometry.push_back(fcl_model(m.mesh, scale / m.radius));
    for (int k = 0; k < poses; ++k) {
      const size_t ia = rng() % ms.size(), ib = rng() % ms.size();
      const Model &ma = ms[ia], &mb = ms[ib];
      Pose pa, pb;
      pa.rotation = random_rotation(rng);
      pb.rotation = random_rotation(rng);
      pa.scale = scale / ma.radius;
      pb.scale = scale / mb.radius;
      pa.position = offset - pa.rotation * (pa.scale * ma.centre);
      const Eigen::Vector3d dir = random_rotation(rng) * Eigen::Vector3d::UnitX();
      pb.position = offset + 3 * scale * dir - pb.rotation * (pb.scale * mb.centre);
      const fcl::CollisionObjectd oa(geometry[ia], to_fcl(pa));
      const auto& gb = geometry[ib];
      fcl::DistanceRequestd request(/*enable_nearest_points=*/true);
      fcl::DistanceResultd apart;
      const fcl::CollisionObjectd far_b(gb, to_fcl(pb));
      fcl::distance(&oa, &far_b, request, apart);
      pb.position += apart.nearest_points[0] - apart.nearest_points[1];
      fcl::DistanceResultd touching;
      const fcl::CollisionObjectd near_b(gb, to_fcl(pb));
      fcl::distance(&oa, &near_b, request, touching);
      // The construction worked: the gap is gone up to rounding.
      ASSERT_LT(touching.min_distance, 1e-9 * scale * (1 + offset.norm() / scale)) << ma.name << " vs " << mb.name;
      check_grids({&ma.tree, pa, kDepth}, {&mb.tree, pb, kDepth}, /*exact=*/true,
                  "touching " + ma.name + " vs " + mb.name + " scale " + std::to_string(scale));
      if (::testing::Test::HasFatalFailure()) return;
    }
  }
}

// Exact face and edge contact between boxes, and a flat quad lying on a cube.
TEST(Oracle, SharedFacesHit) {
  const auto& ms = models();
  const Model& cube = ms[ms.size() - 2];
  const Model& quad = ms[ms.size() - 1];
  for (const double scale : {1e-4, 1.0, 1e4})
    for (const Eigen::Vector3d& offset : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1e7, -1e7, 1e7)}) {
      Pose pa, pb;
      pa.scale = pb.scale = scale;
      pa.position = offset;
      for (const Eigen::Vector3d& shift : {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, -1, 0.5),
                                           Eigen::Vector3d(1, 1, 0), Eigen::Vector3d(1, 1, 1)}) {
        pb.position = offset + scale * shift;
        check_grids({&cube.tree, pa, kDepth}, {&cube.tree, pb, kDepth}, /*exact=*/true, "cube faces");
        // The quad on the cube's top face, and rotated 90 degrees about x onto its side.
        pb.position = offset + scale * Eigen::Vector3d(0.5 * shift.x(), 0.25, 1);
        check_grids({&cube.tree, pa, kDepth}, {&quad.tree, pb, kDepth}, true, "quad on cube");
        Pose side = pb;
        side.rotation = Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX());
        side.position = offset + scale * Eigen::Vector3d(0.25, 1, 0.5 * shift.z());
        check_grids({&cube.tree, pa, kDepth}, {&quad.tree, side, kDepth}, true, "quad on cube side");
        if (::testing::Test::HasFatalFailure()) return;
      }
    }
}

// A random point on a mesh's surface (area-weighted triangle, uniform inside).
Eigen::Vector3d surface_point(const Mesh& mesh, std::mt19937& rng) {
  std::vector<double> area;
  double total = 0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d& p = mesh.positions[t[0]];
    total += (mesh.positions[t[1]] - p).cross(mesh.positions[t[2]] - p).norm();
    area.push_back(total);
  }
  const size_t i = size_t(std::lower_bound(area.begin(), area.end(), uniform01(rng) * total) - area.begin());
  const auto& t = mesh.triangles[std::min(i, mesh.triangles.size() - 1)];
  double u = uniform01(rng), v = uniform01(rng);
  if (u + v > 1) u = 1 - u, v = 1 - v;
  const Eigen::Vector3d& p = mesh.positions[t[0]];
  return p + u * (mesh.positions[t[1]] - p) + v * (mesh.positions[t[2]] - p);
}

struct Counts {
  int poses = 0, contacts = 0;
};

// B (radius `small`, A's is 1) centred near a random point of A's surface, at
// most `reach` of its radius away: about half the poses touch.
void small_near_surface(const Model& ma, const Model& mb, const std::shared_ptr<fcl::CollisionGeometryd>& ga,
                        const std::shared_ptr<fcl::CollisionGeometryd>& gb, double small, double reach,
                        std::mt19937& rng, Counts& counts, const std::string& what) {
  Pose pa, pb;
  pa.rotation = random_rotation(rng);
  pb.rotation = random_rotation(rng);
  pa.scale = 1 / ma.radius;
  pb.scale = small / mb.radius;
  pa.position = -(pa.rotation * (pa.scale * ma.centre));
  const Eigen::Vector3d at = pa.apply(surface_point(ma.mesh, rng));
  const Eigen::Vector3d dir = random_rotation(rng) * Eigen::Vector3d::UnitX();
  pb.position = at + reach * small * uniform01(rng) * dir - pb.rotation * (pb.scale * mb.centre);
  const fcl::CollisionObjectd oa(ga, to_fcl(pa)), ob(gb, to_fcl(pb));
  const bool exact = fcl_collide(oa, ob);
  counts.contacts += exact;
  ++counts.poses;
  check_grids({&ma.tree, pa, kDepth}, {&mb.tree, pb, kDepth}, exact, what);
}

// Objects 400x to 4000x smaller than the one they touch (or nearly touch).
TEST(Oracle, SizeRatiosOf400AndMore) {
  const auto& ms = models();
  constexpr double kRatios[] = {400, 1000, 4000};
  // FCL's BVHs, built once: each model at radius 1 and at each small radius.
  std::vector<std::shared_ptr<fcl::CollisionGeometryd>> large;
  std::vector<std::array<std::shared_ptr<fcl::CollisionGeometryd>, 3>> small;
  for (const Model& m : ms) {
    large.push_back(fcl_model(m.mesh, 1 / m.radius));
    small.push_back({});
    for (int r = 0; r < 3; ++r) small.back()[r] = fcl_model(m.mesh, 1 / (kRatios[r] * m.radius));
  }
  std::mt19937 rng(51);
  const int poses = pose_count(600);
  Counts counts;
  for (int k = 0; k < poses; ++k) {
    const size_t ia = rng() % ms.size(), ib = rng() % ms.size();
    const int r = int(rng() % 3);
    small_near_surface(ms[ia], ms[ib], large[ia], small[ib][r], 1 / kRatios[r], 3.0, rng, counts,
                       "pose " + std::to_string(k) + " " + ms[ib].name + " 1/" + std::to_string(int(kRatios[r])) +
                           " on " + ms[ia].name);
    if (::testing::Test::HasFatalFailure()) return;
  }
  std::printf("  %d poses: %d contacts (FCL)\n", counts.poses, counts.contacts);
  EXPECT_GT(counts.contacts, poses * 3 / 10);
  EXPECT_LT(counts.contacts, poses * 7 / 10);
}

// Extreme aspect ratios: a flat quad and a 1000:1 needle against large
// meshes, and a needle against a wall (a flat quad 50x its length).
TEST(Oracle, ExtremeAspectRatios) {
  const auto& ms = models();
  const Model needle = make_model("needle", box_mesh({1, 1e-3, 1e-3}));
  const Model wall = make_model("wall", quad_mesh());
  const Model& quad = ms.back();
  constexpr double kSmall = 0.1, kNeedleOnWall = 1.0 / 50;
  std::vector<std::shared_ptr<fcl::CollisionGeometryd>> large;
  for (const Model& m : ms) large.push_back(fcl_model(m.mesh, 1 / m.radius));
  const auto quad_small = fcl_model(quad.mesh, kSmall / quad.radius);
  const auto needle_small = fcl_model(needle.mesh, kSmall / needle.radius);
  const auto needle_tiny = fcl_model(needle.mesh, kNeedleOnWall / needle.radius);
  const auto wall_large = fcl_model(wall.mesh, 1 / wall.radius);
  std::mt19937 rng(52);
  const int poses = pose_count(450);
  Counts counts;
  for (int k = 0; k < poses; ++k) {
    const size_t ia = rng() % (ms.size() - 2);  // the real meshes
    const int kind = k % 3;
    const std::string what = "pose " + std::to_string(k) + " kind " + std::to_string(kind);
    if (kind == 0) small_near_surface(ms[ia], quad, large[ia], quad_small, kSmall, 2.5, rng, counts, what + " quad");
    if (kind == 1)
      small_near_surface(ms[ia], needle, large[ia], needle_small, kSmall, 2.5, rng, counts, what + " needle");
    if (kind == 2)
      small_near_surface(wall, needle, wall_large, needle_tiny, kNeedleOnWall, 2.5, rng, counts, what + " wall");
    if (::testing::Test::HasFatalFailure()) return;
  }
  std::printf("  %d poses: %d contacts (FCL)\n", counts.poses, counts.contacts);
  EXPECT_GT(counts.contacts, poses * 3 / 10);
  EXPECT_LT(counts.contacts, poses * 7 / 10);
}

}  // namespace
}  // namespace octbake
