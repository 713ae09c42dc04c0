// Writes the five bundled models (the thesis's test objects) as OBJ:
//   make_assets [OUT_DIR]        (default: the current directory)
// Each is a union of closed, tessellated primitives in metres, y up, the
// origin at the centre of the base. Output is fixed-precision text, so the
// committed files are what any machine regenerates.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

namespace {

using V = Eigen::Vector3d;
constexpr double kPi = std::numbers::pi;

struct Model {
  std::vector<V> positions;
  std::vector<std::array<int, 3>> triangles;

  int add(const V& p) {
    positions.push_back(p);
    return static_cast<int>(positions.size()) - 1;
  }
  void tri(int a, int b, int c) { triangles.push_back({a, b, c}); }
  void quad(int a, int b, int c, int d) { tri(a, b, c), tri(a, c, d); }
};

// A surface of revolution around local y: profile[i] = (radius, height).
// Rings of zero radius become a single pole vertex, so the result is closed
// when the profile starts and ends on the axis.
void lathe(Model& m, const Eigen::Affine3d& place, const std::vector<Eigen::Vector2d>& profile, int segments) {
  std::vector<std::vector<int>> rings;
  for (const Eigen::Vector2d& rh : profile) {
    std::vector<int> ring;
    if (rh.x() == 0) {
      ring.assign(segments, m.add(place * V(0, rh.y(), 0)));
    } else {
      for (int j = 0; j < segments; ++j) {
        const double t = 2 * kPi * j / segments;
        ring.push_back(m.add(place * V(rh.x() * std::cos(t), rh.y(), -rh.x() * std::sin(t))));
      }
    }
    rings.push_back(ring);
  }
  for (size_t i = 0; i + 1 < rings.size(); ++i)
    for (int j = 0; j < segments; ++j) {
      const int k = (j + 1) % segments;
      const int a = rings[i][j], b = rings[i][k], c = rings[i + 1][k], d = rings[i + 1][j];
      if (a != b) m.tri(a, b, c);  // skip the zero-area half at a pole
      if (c != d) m.tri(a, c, d);
    }
}

// Closed frustum along local y from 0 to h (a cylinder when r0 == r1), with
// `bands` rings along the side and `caps` rings on each disc.
void frustum(Model& m, const Eigen::Affine3d& place, double r0, double r1, double h, int segments, int bands, int caps) {
  std::vector<Eigen::Vector2d> p;
  for (int i = 0; i < caps; ++i) p.emplace_back(r0 * i / caps, 0);
  for (int i = 0; i <= bands; ++i) p.emplace_back(r0 + (r1 - r0) * i / bands, h * i / bands);
  for (int i = caps - 1; i >= 0; --i) p.emplace_back(r1 * i / caps, h);
  lathe(m, place, p, segments);
}

// Ellipsoid with the given radii, centred on the placement's origin.
void ellipsoid(Model& m, const Eigen::Affine3d& place, const V& radii, int segments, int rings) {
  std::vector<Eigen::Vector2d> p;
  for (int i = 0; i <= rings; ++i) {
    const double phi = kPi * i / rings;
    p.emplace_back(i == 0 || i == rings ? 0.0 : std::sin(phi), -std::cos(phi));
  }
  lathe(m, place * Eigen::Scaling(radii.x(), radii.y(), radii.z()), p, segments);
}

// Axis-aligned (in the placement's frame) box of half extents `half`, each
// face an n x n grid.
void box(Model& m, const Eigen::Affine3d& place, const V& half, int n) {
  for (int axis = 0; axis < 3; ++axis)
    for (int side = -1; side <= 1; side += 2) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      std::vector<int> grid;
      for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) {
          V p;
          p[axis] = side * half[axis];
          p[u] = half[u] * (2.0 * i / n - 1);
          p[v] = half[v] * (2.0 * j / n - 1);
          grid.push_back(m.add(place * p));
        }
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          const int a = grid[i * (n + 1) + j], b = grid[(i + 1) * (n + 1) + j];
          const int c = grid[(i + 1) * (n + 1) + j + 1], d = grid[i * (n + 1) + j + 1];
          if (side > 0) m.quad(a, b, c, d); else m.quad(a, d, c, b);  // outward winding
        }
    }
}

Eigen::Affine3d at(double x, double y, double z) { return Eigen::Affine3d(Eigen::Translation3d(x, y, z)); }
Eigen::Affine3d turn(const Eigen::Affine3d& t, double angle, const V& axis) { return t * Eigen::AngleAxisd(angle, axis.normalized()); }

// ~6 m: a thin trunk and a wide crown of one big and four smaller blobs.
Model tree() {
  Model m;
  frustum(m, at(0, 0, 0), 0.25, 0.18, 3.0, 32, 12, 2);
  ellipsoid(m, at(0, 4.2, 0), V(2.2, 1.8, 2.2), 64, 32);
  for (int k = 0; k < 4; ++k) {
    const double t = kPi / 2 * k + 0.4;
    ellipsoid(m, at(1.5 * std::cos(t), 3.7 + 0.3 * (k % 2), 1.5 * std::sin(t)), V(1.0, 0.8, 1.0), 32, 16);
  }
  return m;
}

// 1.8 m in a T-pose, facing +z, arms along x.
Model human() {
  Model m;
  for (int s = -1; s <= 1; s += 2) {
    frustum(m, at(0.11 * s, 0.06, 0), 0.06, 0.09, 0.84, 24, 12, 2);                      // leg
    box(m, at(0.11 * s, 0.04, 0.05), V(0.055, 0.04, 0.13), 4);                            // foot
    frustum(m, turn(at(0.2 * s, 1.42, 0), -s * kPi / 2, V(0, 0, 1)), 0.055, 0.04, 0.62, 24, 12, 2);  // arm
    ellipsoid(m, at(0.87 * s, 1.42, 0), V(0.06, 0.045, 0.04), 16, 8);                     // hand
  }
  ellipsoid(m, at(0, 0.95, 0), V(0.19, 0.13, 0.12), 32, 16);    // hips
  frustum(m, at(0, 0.92, 0), 0.15, 0.2, 0.55, 32, 12, 3);        // torso
  ellipsoid(m, at(0, 1.44, 0), V(0.23, 0.07, 0.12), 32, 16);     // shoulders
  frustum(m, at(0, 1.47, 0), 0.05, 0.05, 0.12, 16, 4, 2);        // neck
  ellipsoid(m, at(0, 1.685, 0), V(0.09, 0.115, 0.1), 48, 24);    // head
  return m;
}

// 2 m tall truncated cone, 2 m across at the base.
Model frustum_model() {
  Model m;
  frustum(m, at(0, 0, 0), 1.0, 0.5, 2.0, 128, 16, 8);
  return m;
}

// 3 m tall, facing +z: body, four legs, head, a curled trunk, big flat ears, tail.
Model elephant() {
  Model m;
  ellipsoid(m, at(0, 1.95, 0), V(0.95, 0.95, 1.6), 64, 32);
  for (int sx = -1; sx <= 1; sx += 2)
    for (int sz = -1; sz <= 1; sz += 2) frustum(m, at(0.5 * sx, 0, 0.95 * sz), 0.27, 0.3, 1.7, 32, 12, 2);
  ellipsoid(m, at(0, 2.45, 1.75), V(0.55, 0.55, 0.5), 48, 24);
  // Trunk: a chain of tapering frustums bending down in the y-z plane.
  V base(0, 2.25, 2.15);
  double r = 0.2, angle = 0.7;  // from the horizontal, turning downwards
  for (int k = 0; k < 8; ++k) {
    const double len = 0.28;
    const V dir(0, -std::sin(angle), std::cos(angle));
    const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(V(0, 1, 0), dir);
    frustum(m, at(base.x(), base.y(), base.z()) * q, r, r * 0.87, len, 24, 3, 1);
    base += dir * len * 0.95;
    r *= 0.87;
    angle += 0.22;
  }
  for (int s = -1; s <= 1; s += 2)  // ears: large, thin, flat
    ellipsoid(m, turn(at(0.62 * s, 2.3, 1.45), s * 0.25, V(0, 1, 0)), V(0.05, 0.65, 0.6), 48, 24);
  frustum(m, turn(at(0, 2.0, -1.5), -2.6, V(1, 0, 0)), 0.05, 0.03, 0.8, 12, 4, 1);  // tail
  return m;
}

// 4.5 m long (along z), 1.8 m wide, 1.45 m tall: body, lower cabin, four wheels.
Model car() {
  Model m;
  box(m, at(0, 0.65, 0), V(0.9, 0.35, 2.25), 16);
  box(m, at(0, 1.2, -0.2), V(0.78, 0.25, 1.1), 12);
  for (int sx = -1; sx <= 1; sx += 2)
    for (int sz = -1; sz <= 1; sz += 2)
      frustum(m, turn(at(0.95 * sx - 0.125, 0.34, 1.45 * sz), -kPi / 2, V(0, 0, 1)), 0.34, 0.34, 0.25, 48, 2, 4);
  return m;
}

bool write_obj(const std::string& path, const std::string& name, const Model& m) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return false;
  std::fprintf(f, "# %s: generated by assets/generator/make_assets.cpp, metres, y up\n", name.c_str());
  std::fprintf(f, "# %zu vertices, %zu triangles\no %s\n", m.positions.size(), m.triangles.size(), name.c_str());
  for (const V& p : m.positions) {
    // Never print "-0.000000": same bytes whatever the sign of a tiny value.
    double c[3] = {p.x(), p.y(), p.z()};
    for (double& x : c)
      if (std::fabs(x) < 5e-7) x = 0;
    std::fprintf(f, "v %.6f %.6f %.6f\n", c[0], c[1], c[2]);
  }
  for (const auto& t : m.triangles) std::fprintf(f, "f %d %d %d\n", t[0] + 1, t[1] + 1, t[2] + 1);
  return std::fclose(f) == 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string dir = argc > 1 ? argv[1] : ".";
  const std::pair<const char*, Model> models[] = {
      {"tree", tree()}, {"human", human()}, {"frustum", frustum_model()}, {"elephant", elephant()}, {"car", car()}};
  for (const auto& [name, model] : models) {
    const std::string path = dir + "/" + name + ".obj";
    if (!write_obj(path, name, model)) {
      std::fprintf(stderr, "make_assets: error: cannot write %s\n", path.c_str());
      return 1;
    }
    std::printf("%s: %zu vertices, %zu triangles\n", path.c_str(), model.positions.size(), model.triangles.size());
  }
  return 0;
}
