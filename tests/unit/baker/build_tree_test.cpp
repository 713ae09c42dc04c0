// build_tree: conservative surface coverage, nesting, vertices mode against a
// brute-force rule, solid fill of closed meshes, flat and degenerate meshes.
#include "build_tree.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "random_soup.h"
#include "seeded_random.h"

namespace octbake {
namespace {

using V = Eigen::Vector3d;

using test::random_point;
using test::uniform;

// Dense occupancy of one depth (depth <= 7 keeps it small).
struct Grid {
  int d;
  std::vector<uint8_t> bits;
  Grid(const OctreeMasks& t, int depth) : d(depth), bits(size_t{1} << (3 * depth), 0) {
    for (const BoxCoord& c : t.boxes(depth)) bits[index(c)] = 1;
  }
  size_t index(BoxCoord c) const { return c.x | (size_t{c.y} << d) | (size_t{c.z} << (2 * d)); }
  bool at(BoxCoord c) const { return bits[index(c)] != 0; }
  size_t count() const { return std::count(bits.begin(), bits.end(), 1); }
};

// True when point p lies in some occupied box of depth d. Near a box face the
// point may belong to either neighbour, so both candidates are tried.
bool covered(const OctreeMasks& t, const Grid& grid, const V& p) {
  const int64_t n = int64_t{1} << grid.d;
  int64_t lo[3], hi[3];
  for (int i = 0; i < 3; ++i) {
    const double extent = t.bounds.max[i] - t.bounds.min[i];
    const double u = extent > 0 ? (p[i] - t.bounds.min[i]) / extent * double(n) : 0.0;
    lo[i] = std::clamp<int64_t>(int64_t(std::floor(u - 1e-6)), 0, n - 1);
    hi[i] = std::clamp<int64_t>(int64_t(std::floor(u + 1e-6)), 0, n - 1);
  }
  for (int64_t x = lo[0]; x <= hi[0]; ++x)
    for (int64_t y = lo[1]; y <= hi[1]; ++y)
      for (int64_t z = lo[2]; z <= hi[2]; ++z)
        if (grid.at({uint32_t(x), uint32_t(y), uint32_t(z)})) return true;
  return false;
}

// Every sample of every triangle (barycentric grid incl. edges and corners)
// lies in an occupied box at every depth 1..t.depth().
void expect_surface_covered(const Mesh& mesh, const OctreeMasks& t, int steps) {
  for (int d = 1; d <= t.depth(); ++d) {
    const Grid grid(t, d);
    size_t misses = 0;
    for (const auto& tri : mesh.triangles) {
      const V &a = mesh.positions[tri[0]], &b = mesh.positions[tri[1]], &c = mesh.positions[tri[2]];
      for (int i = 0; i <= steps; ++i)
        for (int j = 0; i + j <= steps; ++j) {
          const V p = a + (double(i) / steps) * (b - a) + (double(j) / steps) * (c - a);
          misses += !covered(t, grid, p);
        }
    }
    EXPECT_EQ(misses, 0u) << "depth " << d;
  }
}

// Every occupied box's parent is occupied, and the masks agree with boxes().
void expect_nested(const OctreeMasks& t) {
  for (int d = 1; d <= t.depth(); ++d) {
    const Grid parent(t, d - 1);
    const std::vector<BoxCoord> boxes = t.boxes(d);
    EXPECT_EQ(boxes.size(), t.box_count(d));
    for (const BoxCoord& c : boxes) EXPECT_TRUE(parent.at({c.x / 2, c.y / 2, c.z / 2}));
  }
}

using test::random_soup;

Mesh cube_mesh() {
  Mesh m;
  for (int i = 0; i < 8; ++i) m.positions.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  // Two triangles per face, corners indexed by bits (x, y, z).
  const uint32_t faces[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  for (const auto& f : faces) {
    m.triangles.push_back({f[0], f[1], f[2]});
    m.triangles.push_back({f[0], f[2], f[3]});
  }
  return m;
}

// UV sphere of radius r (closed), or an open cylinder when `cylinder`.
Mesh lathe(int segments, int rings, double r, bool cylinder) {
  Mesh m;
  for (int i = 0; i <= rings; ++i) {
    const double phi = std::numbers::pi * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double theta = 2 * std::numbers::pi * j / segments;
      const double rho = cylinder ? r : r * std::sin(phi);
      const double z = cylinder ? r * (1 - 2.0 * i / rings) : r * std::cos(phi);
      m.positions.emplace_back(rho * std::cos(theta), rho * std::sin(theta), z);
    }
  }
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const uint32_t a = i * segments + j, b = i * segments + (j + 1) % segments;
      const uint32_t c = a + segments, d = b + segments;
      m.triangles.push_back({a, c, b});
      m.triangles.push_back({b, c, d});
    }
  return m;
}

Mesh load_asset(const std::string& name) {
  Result<Mesh> r = import_mesh(std::string(OCTBAKE_SOURCE_DIR) + "/assets/" + name + ".obj");
  EXPECT_TRUE(r.ok()) << name << ": " << (r.ok() ? "" : r.error().message);
  return r.ok() ? std::move(r).value() : Mesh{};
}

TEST(BuildTree, AssetsSurfaceIsConservativeNestedAndSparse) {
  for (const char* name : {"tree", "human", "frustum", "elephant", "car"}) {
    SCOPED_TRACE(name);
    const Mesh mesh = load_asset(name);
    if (mesh.triangles.empty()) continue;
    const OctreeMasks t = build_tree(mesh, /*depth=*/6, Occupancy::surface);
    ASSERT_EQ(t.depth(), 6);
    expect_surface_covered(mesh, t, /*steps=*/2);  // corners and edge midpoints
    expect_nested(t);
    EXPECT_LT(double(t.box_count(5)) / double(1 << 15), 0.5);
  }
}

TEST(BuildTree, RandomSoupsSurfaceIsConservativeNestedAndSparse) {
  std::mt19937 g(42);
  for (int round = 0; round < 6; ++round) {
    const Mesh mesh = random_soup(g, /*triangles=*/40, /*size=*/round < 3 ? 0.3 : 0.02);
    const OctreeMasks t = build_tree(mesh, /*depth=*/6, Occupancy::surface);
    expect_surface_covered(mesh, t, /*steps=*/12);
    expect_nested(t);
    EXPECT_LT(double(t.box_count(4)) / 4096.0, 0.5);
    EXPECT_GT(t.box_count(6), 40u);
  }
}

TEST(BuildTree, IsDeterministic) {
  std::mt19937 g(5);
  const Mesh mesh = random_soup(g, 200, 0.2);
  for (Occupancy mode : {Occupancy::surface, Occupancy::solid, Occupancy::vertices})
    EXPECT_EQ(build_tree(mesh, 5, mode), build_tree(mesh, 5, mode));
}

// Thesis rule by brute force: every box of every depth against every vertex,
// closed boxes grown by the documented pad.
TEST(BuildTree, VerticesModeEqualsBruteForce) {
  std::mt19937 g(11);
  for (int round = 0; round < 4; ++round) {
    Mesh mesh;
    for (int i = 0; i < 30; ++i) mesh.positions.push_back(random_point(g, -2, 3));
    // Vertices exactly on box faces, edges and corners of the coarse depths.
    for (int i = 0; i < 10; ++i)
      mesh.positions.emplace_back(-2 + 5.0 * (g() % 9) / 8, -2 + 5.0 * (g() % 9) / 8, -2 + 5.0 * (g() % 5) / 4);
    mesh.positions.emplace_back(-2, -2, -2);
    mesh.positions.emplace_back(3, 3, 3);
    for (uint32_t i = 0; i + 2 < mesh.positions.size(); i += 3) mesh.triangles.push_back({i, i + 1, i + 2});

    const OctreeMasks t = build_tree(mesh, /*depth=*/4, Occupancy::vertices);
    const double pad = occupancy_pad(t.bounds);
    for (int d = 1; d <= 4; ++d) {
      const Grid grid(t, d);
      const uint32_t n = 1u << d;
      for (uint32_t z = 0; z < n; ++z)
        for (uint32_t y = 0; y < n; ++y)
          for (uint32_t x = 0; x < n; ++x) {
            const Aabb b = t.box_bounds(d, {x, y, z});
            bool holds = false;
            for (const V& p : mesh.positions)
              holds |= ((p - b.min).array() >= -pad).all() && ((b.max - p).array() >= -pad).all();
            ASSERT_EQ(grid.at({x, y, z}), holds) << "depth " << d << " box " << x << "," << y << "," << z;
          }
    }
  }
}

TEST(BuildTree, SolidFillsClosedCube) {
  const Mesh cube = cube_mesh();
  for (int d = 3; d <= 5; ++d) {
    const OctreeMasks solid = build_tree(cube, d, Occupancy::solid);
    const OctreeMasks surface = build_tree(cube, d, Occupancy::surface);
    EXPECT_EQ(solid.box_count(d), uint64_t{1} << (3 * d));  // the cube is its own bounds
    EXPECT_LT(surface.box_count(d), solid.box_count(d));
    expect_nested(solid);
  }
}

TEST(BuildTree, SolidFillsSphereAndNothingOutside) {
  const double r = 1.0;
  const int segments = 48;
  const Mesh sphere = lathe(segments, segments / 2, r, /*cylinder=*/false);
  // Everything within this radius is inside the polyhedron.
  const double inner = r * std::cos(std::numbers::pi / (segments / 2)) * std::cos(std::numbers::pi / segments);
  for (int d = 3; d <= 5; ++d) {
    const OctreeMasks solid = build_tree(sphere, d, Occupancy::solid);
    const OctreeMasks surface = build_tree(sphere, d, Occupancy::surface);
    const Grid sg(solid, d), fg(surface, d);
    const uint32_t n = 1u << d;
    size_t interior = 0;
    for (uint32_t z = 0; z < n; ++z)
      for (uint32_t y = 0; y < n; ++y)
        for (uint32_t x = 0; x < n; ++x) {
          const Aabb b = solid.box_bounds(d, {x, y, z});
          const V nearest = V::Zero().cwiseMax(b.min).cwiseMin(b.max);
          const V farthest = b.min.cwiseAbs().cwiseMax(b.max.cwiseAbs());
          if (fg.at({x, y, z})) {
            EXPECT_TRUE(sg.at({x, y, z}));  // solid contains surface
          }
          if (farthest.norm() < inner) {
            EXPECT_TRUE(sg.at({x, y, z})) << "interior box left empty";
            ++interior;
          }
          if (nearest.norm() > r * 1.000001) {
            EXPECT_FALSE(sg.at({x, y, z})) << "box outside the ball";
          }
        }
    EXPECT_GT(interior, 0u);
    expect_nested(solid);
  }
}

TEST(BuildTree, SolidOfOpenMeshEqualsSurface) {
  Mesh quad;
  quad.positions = {V(0, 0, 0), V(2, 0, 0.5), V(2, 1, 1), V(0, 1, 0.5)};
  quad.triangles = {{0, 1, 2}, {0, 2, 3}};
  const Mesh tube = lathe(24, 6, 1.0, /*cylinder=*/true);
  for (int d = 3; d <= 5; ++d) {
    EXPECT_EQ(build_tree(quad, d, Occupancy::solid), build_tree(quad, d, Occupancy::surface));
    EXPECT_EQ(build_tree(tube, d, Occupancy::solid), build_tree(tube, d, Occupancy::surface));
  }
}

TEST(BuildTree, SolidBeyondFillDepthKeepsInterior) {
  // A unit cube in bounds 16 wide (a point at the far corner), so depth 9
  // stays small: the cube spans boxes 0..31 per axis.
  Mesh m = cube_mesh();
  m.positions.emplace_back(16, 16, 16);
  m.triangles.push_back({8, 8, 8});
  const int d = kSolidFillDepth + 1;
  const OctreeMasks t = build_tree(m, d, Occupancy::solid);
  const OctreeMasks surface = build_tree(m, d, Occupancy::surface);
  const std::vector<BoxCoord> boxes = t.boxes(d);
  std::vector<uint64_t> keys;  // sorted (z, y, x) for lookups
  for (const BoxCoord& c : boxes) keys.push_back(uint64_t{c.z} << 40 | uint64_t{c.y} << 20 | c.x);
  std::sort(keys.begin(), keys.end());
  auto has = [&](BoxCoord c) {
    return std::binary_search(keys.begin(), keys.end(), uint64_t{c.z} << 40 | uint64_t{c.y} << 20 | c.x);
  };
  // Interior under depth-8 boxes that do not touch the surface is full
  // (depth-8 boxes 1..14, so depth-9 boxes 2..29); nothing beyond the cube.
  for (uint32_t z = 2; z <= 29; z += 3)
    for (uint32_t y = 2; y <= 29; y += 3)
      for (uint32_t x = 2; x <= 29; ++x) EXPECT_TRUE(has({x, y, z})) << x << "," << y << "," << z;
  size_t far = 0;
  for (const BoxCoord& c : boxes) far += (c.x > 32 || c.y > 32 || c.z > 32);
  EXPECT_EQ(far, 1u);  // the corner point's box
  EXPECT_GT(t.box_count(d), surface.box_count(d) + 20000);
  expect_nested(t);
}

TEST(BuildTree, FlatQuadAtDepth6) {
  Mesh quad;
  quad.positions = {V(0, 0, 0), V(4, 0, 0), V(4, 2, 0), V(0, 2, 0)};
  quad.triangles = {{0, 1, 2}, {0, 2, 3}};
  const OctreeMasks t = build_tree(quad, 6, Occupancy::surface);
  EXPECT_EQ(t.bounds.min.z(), t.bounds.max.z());
  // Boxes are flat on z, so every box lies in the quad's plane and covers
  // it; the 64 boxes of a column are one box, marked once.
  EXPECT_EQ(t.box_count(6), uint64_t{1} << 12);
  expect_surface_covered(quad, t, 16);

  // One triangle of it: half the columns, not everything.
  Mesh half = quad;
  half.triangles = {{0, 1, 2}};
  const OctreeMasks h = build_tree(half, 6, Occupancy::surface);
  expect_surface_covered(half, h, 32);
  EXPECT_LT(h.box_count(6), t.box_count(6) * 6 / 10);
  EXPECT_GT(h.box_count(6), t.box_count(6) * 4 / 10);
}

TEST(BuildTree, DegenerateTriangleStillOccupies) {
  Mesh m;
  // A proper triangle in one corner, and zero-area ones across the bounds: a
  // segment along the main diagonal and a point.
  m.positions = {V(0, 0, 0), V(0.1, 0, 0), V(0, 0.1, 0), V(1, 1, 1), V(0.25, 0.25, 0.25), V(0.9, 0.1, 0.5)};
  m.triangles = {{0, 1, 2}, {0, 3, 4}, {5, 5, 5}};
  const OctreeMasks t = build_tree(m, 6, Occupancy::surface);
  expect_surface_covered(m, t, 64);
  // The diagonal occupies at least its own 64 boxes at depth 6.
  EXPECT_GE(t.box_count(6), 64u);
  EXPECT_LT(t.box_count(6), 2000u);
}

TEST(BuildTree, SinglePointMeshDoesNotBreak) {
  Mesh m;
  m.positions = {V(1, 2, 3)};
  m.triangles = {{0, 0, 0}};
  // Every box is the same point: one of them is marked per depth, so depth
  // 12 is as cheap as depth 1 (marking all gave 8^d: 40 s at depth 10).
  for (Occupancy mode : {Occupancy::surface, Occupancy::solid, Occupancy::vertices}) {
    const OctreeMasks t = build_tree(m, 12, mode);
    for (int d = 0; d <= 12; ++d) {
      EXPECT_EQ(t.box_count(d), 1u) << d;
      const std::vector<BoxCoord> boxes = t.boxes(d);  // the low corner's box, where the point lies
      ASSERT_EQ(boxes.size(), 1u);
      EXPECT_EQ(boxes[0].x | boxes[0].y | boxes[0].z, 0u) << d;
    }
  }
}

}  // namespace
}  // namespace octbake
