#include "build_tree.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>

#include "occupancy.h"

namespace octbake {
namespace {

// A primitive handed down the tree: a triangle, or in vertices mode a point
// stored as a triangle with three equal corners (the separating axis test
// then reduces to closed-box containment).
struct Prim {
  Eigen::Vector3d v[3];
  Eigen::Vector3d lo, hi;  // its bounds, for picking candidate children cheaply
};

Prim make_prim(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  return {{a, b, c}, a.cwiseMin(b).cwiseMin(c), a.cwiseMax(b).cwiseMax(c)};
}

BoxCoord child_coord(BoxCoord c, uint32_t j) {
  return {2 * c.x + (j & 1u), 2 * c.y + ((j >> 1) & 1u), 2 * c.z + ((j >> 2) & 1u)};
}

// Dense index of box c in a 2^d grid.
uint64_t grid_index(int d, BoxCoord c) {
  return uint64_t{c.x} | (uint64_t{c.y} << d) | (uint64_t{c.z} << (2 * d));
}

// Solid mode's flood fill result as a pyramid: any[d][grid_index(d, c)] says
// whether box c of depth d holds an interior (enclosed, empty) box of depth
// `depth`; at d == depth it says that box is wholly interior.
struct Interior {
  int depth = 0;
  std::vector<std::vector<uint8_t>> any;
  bool contains(int d, BoxCoord c) const { return any[d][grid_index(d, c)] != 0; }
};

class TreeBuilder {
 public:
  TreeBuilder(const std::vector<Prim>& prims, const Aabb& bounds, int depth, double pad, const Interior* interior)
      : prims_(prims), bounds_(bounds), depth_(depth), pad_(pad), interior_(interior), scratch_(depth) {
    for (int d = 0; d <= depth; ++d) size_[d] = (bounds.max - bounds.min) / double(uint64_t{1} << d);
  }

  OctreeMasks run() {
    masks_.assign(depth_, {});
    work_.resize(prims_.size());
    for (size_t i = 0; i < prims_.size(); ++i) work_[i] = static_cast<uint32_t>(i);
    visit(0, BoxCoord{}, 0, work_.size(), false);
    return OctreeMasks{bounds_, std::move(masks_)};
  }

 private:
  // Same arithmetic as OctreeMasks::box_bounds, so both agree bit for bit.
  Aabb box(int d, BoxCoord c) const {
    const Eigen::Vector3d lo = bounds_.min + size_[d].cwiseProduct(Eigen::Vector3d(c.x, c.y, c.z));
    return {lo, lo + size_[d]};
  }

  // Box c of depth d is occupied; work_[begin, end) are the primitives that
  // touch it; `full` means it is wholly interior (solid), so is its subtree.
  // Depth-first in octant order appends each depth's masks in Morton order.
  void visit(int d, BoxCoord c, size_t begin, size_t end, bool full) {
    if (d == depth_) return;
    const int cd = d + 1;
    const bool last = cd == depth_;
    std::array<BoxCoord, 8> cc;
    std::array<Aabb, 8> child;
    for (uint32_t j = 0; j < 8; ++j) {
      cc[j] = child_coord(c, j);
      child[j] = box(cd, cc[j]);
    }
    uint8_t mask = full ? 0xFF : 0;
    std::array<bool, 8> child_full{};
    child_full.fill(full);
    auto& lists = scratch_[d];
    for (auto& l : lists) l.clear();

    if (!full) {
      if (interior_ != nullptr && cd <= interior_->depth) {
        for (uint32_t j = 0; j < 8; ++j) {
          if (!interior_->contains(cd, cc[j])) continue;
          mask |= uint8_t(1u << j);
          child_full[j] = cd == interior_->depth;
        }
      }
      // Which halves a primitive can reach per axis: the same comparisons as
      // the box-normal part of the overlap test, done once for all children.
      const Eigen::Vector3d low_hi = child[0].max, high_lo = child[7].min;
      for (size_t k = begin; k < end; ++k) {
        const uint32_t t = work_[k];
        const Prim& p = prims_[t];
        uint32_t half_ok[3];
        for (int i = 0; i < 3; ++i)
          half_ok[i] = (p.lo[i] <= low_hi[i] + pad_ ? 1u : 0u) | (p.hi[i] >= high_lo[i] - pad_ ? 2u : 0u);
        for (uint32_t j = 0; j < 8; ++j) {
          if (!(half_ok[0] >> (j & 1u) & 1u) || !(half_ok[1] >> ((j >> 1) & 1u) & 1u) ||
              !(half_ok[2] >> ((j >> 2) & 1u) & 1u))
            continue;
          if (child_full[j] || (last && (mask >> j & 1u))) continue;
          if (!triangle_overlaps_box(p.v[0], p.v[1], p.v[2], child[j].min, child[j].max, pad_)) continue;
          mask |= uint8_t(1u << j);
          if (!last) lists[j].push_back(t);
        }
        if (last && mask == 0xFF) break;
      }
    }
    masks_[d].push_back(mask);
    if (last) return;

    const size_t base = work_.size();
    std::array<size_t, 9> start{};
    for (uint32_t j = 0; j < 8; ++j) {
      start[j] = work_.size();
      work_.insert(work_.end(), lists[j].begin(), lists[j].end());
    }
    start[8] = work_.size();
    for (uint32_t j = 0; j < 8; ++j)
      if (mask >> j & 1u) visit(cd, cc[j], start[j], start[j + 1], child_full[j]);
    work_.resize(base);
  }

  const std::vector<Prim>& prims_;
  Aabb bounds_;
  int depth_;
  double pad_;
  const Interior* interior_;
  std::array<Eigen::Vector3d, 13> size_;
  std::vector<std::vector<uint8_t>> masks_;
  std::vector<uint32_t> work_;  // stacked primitive lists, one segment per open box
  std::vector<std::array<std::vector<uint32_t>, 8>> scratch_;  // per depth, reused
};

// Flood fill of empty space from outside the 2^d grid (6-connected) over the
// surface boxes of `surface`; what it cannot reach is interior.
Interior fill_interior(const OctreeMasks& surface) {
  const int d = surface.depth();
  const uint32_t n = 1u << d;
  constexpr uint8_t kEmpty = 0, kWall = 1, kOutside = 2;
  std::vector<uint8_t> state(uint64_t{n} * n * n, kEmpty);
  for (const BoxCoord& c : surface.boxes(d)) state[grid_index(d, c)] = kWall;

  std::vector<uint32_t> frontier, next;
  auto reach = [&](uint32_t x, uint32_t y, uint32_t z) {
    const uint64_t i = grid_index(d, {x, y, z});
    if (state[i] != kEmpty) return;
    state[i] = kOutside;
    next.push_back(static_cast<uint32_t>(i));
  };
  for (uint32_t a = 0; a < n; ++a) {
    for (uint32_t b = 0; b < n; ++b) {
      reach(0, a, b), reach(n - 1, a, b);
      reach(a, 0, b), reach(a, n - 1, b);
      reach(a, b, 0), reach(a, b, n - 1);
    }
  }
  // Breadth first with two frontiers: memory follows the wavefront, not the grid.
  while (!next.empty()) {
    frontier.swap(next);
    next.clear();
    for (const uint32_t i : frontier) {
      const uint32_t x = i & (n - 1), y = (i >> d) & (n - 1), z = i >> (2 * d);
      if (x > 0) reach(x - 1, y, z);
      if (x + 1 < n) reach(x + 1, y, z);
      if (y > 0) reach(x, y - 1, z);
      if (y + 1 < n) reach(x, y + 1, z);
      if (z > 0) reach(x, y, z - 1);
      if (z + 1 < n) reach(x, y, z + 1);
    }
  }

  Interior in;
  in.depth = d;
  in.any.resize(d + 1);
  in.any[d].resize(state.size());
  for (size_t i = 0; i < state.size(); ++i) in.any[d][i] = state[i] == kEmpty;
  for (int k = d - 1; k >= 0; --k) {
    const uint32_t m = 1u << k;
    in.any[k].assign(uint64_t{m} * m * m, 0);
    for (uint32_t z = 0; z < m; ++z)
      for (uint32_t y = 0; y < m; ++y)
        for (uint32_t x = 0; x < m; ++x) {
          uint8_t any = 0;
          for (uint32_t j = 0; j < 8; ++j) any |= in.any[k + 1][grid_index(k + 1, child_coord({x, y, z}, j))];
          in.any[k][grid_index(k, {x, y, z})] = any;
        }
  }
  return in;
}

}  // namespace

double occupancy_pad(const Aabb& bounds) {
  const double extent = (bounds.max - bounds.min).maxCoeff();
  const double magnitude = std::max(bounds.min.cwiseAbs().maxCoeff(), bounds.max.cwiseAbs().maxCoeff());
  constexpr double kRelative = 1e-9;
  constexpr double kUlps = 64 * std::numeric_limits<double>::epsilon();
  return kRelative * extent + kUlps * magnitude + std::numeric_limits<double>::min();
}

OctreeMasks build_tree(const Mesh& mesh, int depth, Occupancy mode) {
  assert(depth >= 1 && depth <= 12);
  assert(!mesh.positions.empty());
  Aabb bounds{mesh.positions.front(), mesh.positions.front()};
  for (const Eigen::Vector3d& p : mesh.positions) {
    bounds.min = bounds.min.cwiseMin(p);
    bounds.max = bounds.max.cwiseMax(p);
  }
  const double pad = occupancy_pad(bounds);

  std::vector<Prim> prims;
  if (mode == Occupancy::vertices) {
    prims.reserve(mesh.positions.size());
    for (const Eigen::Vector3d& p : mesh.positions) prims.push_back(make_prim(p, p, p));
  } else {
    prims.reserve(mesh.triangles.size());
    for (const auto& t : mesh.triangles) prims.push_back(make_prim(mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]));
  }

  if (mode != Occupancy::solid) return TreeBuilder(prims, bounds, depth, pad, nullptr).run();
  const int fill_depth = std::min(depth, kSolidFillDepth);
  const Interior interior = fill_interior(TreeBuilder(prims, bounds, fill_depth, pad, nullptr).run());
  return TreeBuilder(prims, bounds, depth, pad, &interior).run();
}

}  // namespace octbake
