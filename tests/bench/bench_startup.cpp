// Scene start-up: 210 object trees from baked files versus rebuilt from meshes.
//
// Five models (assets/*.obj when present, else seeded procedural meshes) are
// baked at depth 6 into a folder. "Load" is what a scene does: ModelLibrary
// opens the 5 files, loads each model once at depth 3 and at depth 6, and
// 210 instances point at those trees. "Rebuild" calls build_tree once per
// instance (210), and, as the fair lower bound, once per model and depth (10).
// Best of N runs, one CSV line per measure. Build with -DOCTBAKE_BENCH=ON:
//   ./build/tests/bench_startup [runs=50]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "build_tree.h"
#include "import.h"
#include "octbake/baked_file.h"

namespace octbake {
namespace {

constexpr int kInstances = 210;
constexpr int kBakedDepth = 6;
constexpr int kShallowDepth = 3;

double unit(std::mt19937& rng) { return rng() / 4294967296.0; }

// A closed (u, v) grid surface: `f(u, v)` in [0,1)^2 gives the point.
template <class F>
Mesh grid_mesh(int nu, int nv, F f) {
  Mesh m;
  for (int j = 0; j <= nv; ++j) {
    for (int i = 0; i < nu; ++i) m.positions.push_back(f(double(i) / nu, double(j) / nv));
  }
  for (int j = 0; j < nv; ++j) {
    for (int i = 0; i < nu; ++i) {
      const uint32_t a = j * nu + i, b = j * nu + (i + 1) % nu, c = a + nu, d = b + nu;
      m.triangles.push_back({a, b, d});
      m.triangles.push_back({a, d, c});
    }
  }
  return m;
}

std::vector<std::pair<std::string, Mesh>> procedural_models() {
  using std::cos, std::sin;
  constexpr double kTau = 2 * std::numbers::pi;
  std::vector<std::pair<std::string, Mesh>> models;
  models.emplace_back("sphere", grid_mesh(96, 48, [&](double u, double v) {
    const double t = v * std::numbers::pi, p = u * kTau;
    return Eigen::Vector3d(sin(t) * cos(p), sin(t) * sin(p), cos(t));
  }));
  models.emplace_back("torus", grid_mesh(128, 64, [&](double u, double v) {
    const double p = u * kTau, q = v * kTau;
    return Eigen::Vector3d((1.5 + 0.5 * cos(q)) * cos(p), (1.5 + 0.5 * cos(q)) * sin(p), 0.5 * sin(q));
  }));
  models.emplace_back("column", grid_mesh(128, 48, [&](double u, double v) {
    const double r = 0.3 + 0.1 * sin(v * 6 * kTau);
    return Eigen::Vector3d(r * cos(u * kTau), r * sin(u * kTau), 4 * v);
  }));
  models.emplace_back("blob", grid_mesh(160, 80, [&](double u, double v) {
    const double t = v * std::numbers::pi, p = u * kTau;
    const double r = 1 + 0.2 * sin(5 * p) * sin(4 * t);
    return Eigen::Vector3d(r * sin(t) * cos(p), r * sin(t) * sin(p), r * cos(t));
  }));
  Mesh soup;  // seeded random triangle soup: small triangles scattered in a box
  std::mt19937 rng(42);
  for (uint32_t i = 0; i < 8000; ++i) {
    const Eigen::Vector3d c(4 * unit(rng), 2 * unit(rng), 2 * unit(rng));
    for (int k = 0; k < 3; ++k) soup.positions.push_back(c + 0.1 * Eigen::Vector3d(unit(rng), unit(rng), unit(rng)));
    soup.triangles.push_back({3 * i, 3 * i + 1, 3 * i + 2});
  }
  models.emplace_back("soup", std::move(soup));
  return models;
}

// assets/*.obj first (sorted), then procedural models up to five.
std::vector<std::pair<std::string, Mesh>> models() {
  std::vector<std::pair<std::string, Mesh>> out;
  const std::filesystem::path assets = std::filesystem::path(OCTBAKE_SOURCE_DIR) / "assets";
  std::vector<std::filesystem::path> objs;
  if (std::filesystem::is_directory(assets)) {
    for (const auto& e : std::filesystem::directory_iterator(assets)) {
      if (e.path().extension() == ".obj") objs.push_back(e.path());
    }
  }
  std::sort(objs.begin(), objs.end());
  for (const auto& p : objs) {
    if (out.size() == 5) break;
    Result<Mesh> mesh = import_mesh(p.string());
    if (mesh) out.emplace_back(p.stem().string(), std::move(mesh).value());
  }
  for (auto& m : procedural_models()) {
    if (out.size() == 5) break;
    out.push_back(std::move(m));
  }
  return out;
}

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

struct Timing {
  double best = 1e300;
  std::vector<double> all;
  void add(double ms) {
    best = std::min(best, ms);
    all.push_back(ms);
  }
  double median() {
    std::sort(all.begin(), all.end());
    return all[all.size() / 2];
  }
};

}  // namespace
}  // namespace octbake

int main(int argc, char** argv) {
  using namespace octbake;
  const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 50;
  const auto meshes = models();
  const std::string dir = std::string(OCTBAKE_BINARY_DIR) + "/bench_startup";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  uint64_t triangles = 0, file_bytes = 0;
  for (const auto& [name, mesh] : meshes) {
    TreeToEncode t;
    t.name = name;
    t.options.depth = kBakedDepth;
    t.masks = build_tree(mesh, kBakedDepth, Occupancy::surface);
    t.triangle_count = mesh.triangles.size();
    t.vertex_count = mesh.positions.size();
    const std::vector<uint8_t> bytes = encode_file({&t, 1}, "bench");
    std::ofstream(dir + "/" + name + ".oct", std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()),
                                                                     std::streamsize(bytes.size()));
    triangles += mesh.triangles.size();
    file_bytes += bytes.size();
  }

  // Load: what a scene of 210 instances does at start-up (page cache warm).
  Timing load;
  uint64_t checksum = 0;
  LoadStats stats;
  for (int r = 0; r < runs; ++r) {
    const auto t0 = Clock::now();
    Result<ModelLibrary> lib = ModelLibrary::open(dir);
    if (!lib) return std::fprintf(stderr, "%s\n", lib.error().message.c_str()), 1;
    std::vector<ObjectTree> trees;  // [model * 2 + (deep ? 1 : 0)]
    for (const auto& [name, mesh] : meshes) {
      for (int depth : {kShallowDepth, kBakedDepth}) {
        Result<ObjectTree> t = lib->load(name, depth);
        if (!t) return std::fprintf(stderr, "%s\n", t.error().message.c_str()), 1;
        trees.push_back(std::move(t).value());
      }
    }
    std::vector<const ObjectTree*> instances(kInstances);
    for (int i = 0; i < kInstances; ++i) instances[i] = &trees[(i % meshes.size()) * 2 + (i / meshes.size()) % 2];
    load.add(ms_since(t0));
    for (const ObjectTree* t : instances) checksum += t->box_count(t->loaded_depth());
    stats = lib->stats();
  }

  // Rebuild: build_tree per instance (a runtime without baking), best of a few.
  Timing rebuild_all, rebuild_models;
  const int slow_runs = std::max(1, std::min(runs, 3));
  for (int r = 0; r < slow_runs; ++r) {
    auto t0 = Clock::now();
    for (int i = 0; i < kInstances; ++i) {
      const int depth = (i / int(meshes.size())) % 2 ? kBakedDepth : kShallowDepth;
      checksum += build_tree(meshes[i % meshes.size()].second, depth, Occupancy::surface).box_count(depth);
    }
    rebuild_all.add(ms_since(t0));
    t0 = Clock::now();
    for (const auto& [name, mesh] : meshes) {
      for (int depth : {kShallowDepth, kBakedDepth}) checksum += build_tree(mesh, depth, Occupancy::surface).depth();
    }
    rebuild_models.add(ms_since(t0));
  }

  std::printf("# %zu models, %llu triangles, %llu baked bytes; load: %llu files, %llu levels, %llu bytes decoded\n",
              meshes.size(), (unsigned long long)triangles, (unsigned long long)file_bytes,
              (unsigned long long)stats.files_opened, (unsigned long long)stats.levels_decoded,
              (unsigned long long)stats.bytes_decompressed);
  std::printf("measure,runs,best_ms,median_ms\n");
  std::printf("load_210_baked,%d,%.4f,%.4f\n", runs, load.best, load.median());
  std::printf("rebuild_210_build_tree,%d,%.2f,%.2f\n", slow_runs, rebuild_all.best, rebuild_all.median());
  std::printf("rebuild_10_build_tree,%d,%.2f,%.2f\n", slow_runs, rebuild_models.best, rebuild_models.median());
  std::printf("# speedup: %.0fx vs 210 rebuilds, %.0fx vs 10 rebuilds (checksum %llu)\n",
              rebuild_all.best / load.best, rebuild_models.best / load.best, (unsigned long long)checksum);
  return 0;
}
