#include "build_tree.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <cmath>
#include <exception>
#include <limits>
#include <mutex>
#include <system_error>
#include <thread>

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

// A subtree still to build: occupied box `coord` of the split depth, the
// primitives that touch it (in the order its parent handed them down) and
// whether it is wholly interior (solid).
struct Subtree {
  BoxCoord coord;
  bool full = false;
  std::vector<uint32_t> prims;
};

// Builds the masks of the levels between a root box and `depth`. With
// `frontier` set it stops at depth `stop` and hands the occupied boxes there
// back as subtrees instead of descending into them.
class TreeBuilder {
 public:
  TreeBuilder(const std::vector<Prim>& prims, const Aabb& bounds, int depth, double pad, const Interior* interior)
      : prims_(prims), bounds_(bounds), depth_(depth), pad_(pad), interior_(interior), scratch_(depth) {
    for (int d = 0; d <= depth; ++d) size_[d] = (bounds.max - bounds.min) / double(uint64_t{1} << d);
    for (int i = 0; i < 3; ++i) flat_[i] = !(bounds.max[i] > bounds.min[i]);
  }

  // masks[d] for d < stop of the whole tree; the boxes of depth `stop`, in
  // Morton order, go to `frontier`.
  std::vector<std::vector<uint8_t>> top(int stop, std::vector<Subtree>& frontier) {
    stop_ = stop;
    frontier_ = &frontier;
    masks_.assign(depth_, {});
    work_.resize(prims_.size());
    for (size_t i = 0; i < prims_.size(); ++i) work_[i] = static_cast<uint32_t>(i);
    visit(0, BoxCoord{}, 0, work_.size(), false);
    return std::move(masks_);
  }

  // masks[d] for d >= root_depth of the subtree under box `root` of depth
  // root_depth (the levels above stay empty).
  std::vector<std::vector<uint8_t>> subtree(int root_depth, const Subtree& root) {
    stop_ = depth_;
    frontier_ = nullptr;
    masks_.assign(depth_, {});
    work_ = root.prims;
    visit(root_depth, root.coord, 0, work_.size(), root.full);
    return std::move(masks_);
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
    if (frontier_ != nullptr && d == stop_) {
      frontier_->push_back({c, full, {work_.begin() + begin, work_.begin() + end}});
      return;
    }
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
          half_ok[i] = (p.lo[i] <= low_hi[i] + pad_ ? 1u : 0u) | (p.hi[i] >= high_lo[i] - pad_ && !flat_[i] ? 2u : 0u);
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
  // Axes on which the bounds have no extent: there both halves of a box are
  // the same box, so only the low one is marked (a point mesh would
  // otherwise fill all 8^d boxes of its depth, a flat one 2^d per column).
  std::array<bool, 3> flat_{};
  Aabb bounds_;
  int depth_;
  double pad_;
  const Interior* interior_;
  int stop_ = 0;
  std::vector<Subtree>* frontier_ = nullptr;
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

// Runs every item i in [0, n) on the calling thread plus helpers that take
// free slots from `budget` (null: none): each thread makes its own worker,
// `make_worker()`, and calls worker(i) for the items it takes. Slots are
// looked for before each item, so threads another job gives back join a
// build in progress. The first exception thrown by any worker stops the rest
// and is rethrown here, after every helper has finished.
template <class MakeWorker>
void run_tasks(size_t n, ThreadBudget* budget, const MakeWorker& make_worker) {
  std::atomic<size_t> next{0};
  std::mutex mu;
  std::exception_ptr failure;
  auto fail = [&] {
    const std::lock_guard lock(mu);
    if (!failure) failure = std::current_exception();
    next.store(n);
  };
  auto helper = [&] {
    try {
      auto worker = make_worker();
      for (size_t i; (i = next.fetch_add(1)) < n;) worker(i);
    } catch (...) {
      fail();
    }
    budget->release();
  };
  {
    std::vector<std::jthread> helpers;  // joined before `failure` is read
    bool spawning = budget != nullptr;
    try {
      auto worker = make_worker();
      for (size_t i; (i = next.fetch_add(1)) < n;) {
        // A helper only when an item is left besides the one this thread takes.
        while (spawning && next.load() < n && budget->try_acquire()) {
          try {
            helpers.emplace_back(helper);
          } catch (const std::system_error&) {  // no thread to be had: go on with those running
            budget->release();
            spawning = false;
          }
        }
        worker(i);
      }
    } catch (...) {
      fail();
    }
  }
  if (failure) std::rethrow_exception(failure);
}

// Split depth: the top levels are built on the calling thread, the subtrees
// below in parallel. Depth 3 gives up to 512 subtrees, enough to balance a
// few threads, while the serial top stays a few percent of a deep build.
constexpr int kSplitDepth = 3;

// build_tree's core for one depth: the top levels serially, then every
// occupied box of the split depth as its own task, largest first; each
// level's masks are the subtrees' masks concatenated in Morton order, so the
// result does not depend on threads or scheduling.
OctreeMasks build_split(const std::vector<Prim>& prims, const Aabb& bounds, int depth, double pad,
                        const Interior* interior, const BuildControl& control) {
  const int split = std::min(depth - 1, kSplitDepth);
  std::vector<Subtree> subtrees;
  std::vector<std::vector<uint8_t>> masks = TreeBuilder(prims, bounds, depth, pad, interior).top(split, subtrees);

  // Progress in primitive references at the split depth: a subtree's share of
  // the work grows with the primitives handed to it (+1: every part counts).
  auto weight = [](const Subtree& s) { return uint64_t{s.prims.size()} + 1; };
  uint64_t total = 0;
  for (const Subtree& s : subtrees) total += weight(s);
  std::mutex progress_mu;
  uint64_t done = 0;
  if (control.progress) control.progress(0, total);

  // Largest first, so the last tasks running are short ones.
  std::vector<uint32_t> order(subtrees.size());
  for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t a, uint32_t b) { return subtrees[a].prims.size() > subtrees[b].prims.size(); });
  std::vector<std::vector<std::vector<uint8_t>>> parts(subtrees.size());
  // One builder per thread, so its scratch lists are reused from task to task.
  run_tasks(order.size(), control.threads, [&] {
    return [&, builder = TreeBuilder(prims, bounds, depth, pad, interior)](size_t k) mutable {
      Subtree& s = subtrees[order[k]];
      parts[order[k]] = builder.subtree(split, s);
      const uint64_t w = weight(s);
      std::vector<uint32_t>().swap(s.prims);
      if (!control.progress) return;
      const std::lock_guard lock(progress_mu);
      done += w;
      control.progress(done, total);
    };
  });

  for (int d = split; d < depth; ++d) {
    size_t size = 0;
    for (const auto& part : parts) size += part[d].size();
    masks[d].reserve(size);
    for (auto& part : parts) {
      masks[d].insert(masks[d].end(), part[d].begin(), part[d].end());
      std::vector<uint8_t>().swap(part[d]);  // keep the peak near one copy of the tree
    }
  }
  return OctreeMasks{bounds, std::move(masks)};
}

}  // namespace

double occupancy_pad(const Aabb& bounds) {
  const double extent = (bounds.max - bounds.min).maxCoeff();
  const double magnitude = max_abs_coordinate(bounds);
  constexpr double kRelative = 1e-9;
  constexpr double kUlps = 64 * std::numeric_limits<double>::epsilon();
  return kRelative * extent + kUlps * magnitude + std::numeric_limits<double>::min();
}

OctreeMasks build_tree(const Mesh& mesh, int depth, Occupancy mode, const BuildControl& control) {
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

  if (mode != Occupancy::solid) return build_split(prims, bounds, depth, pad, nullptr, control);
  // The fill grid is a cheap first pass; only the full-depth build reports progress.
  const int fill_depth = std::min(depth, kSolidFillDepth);
  const Interior interior =
      fill_interior(build_split(prims, bounds, fill_depth, pad, nullptr, {control.threads, {}}));
  return build_split(prims, bounds, depth, pad, &interior, control);
}

}  // namespace octbake
