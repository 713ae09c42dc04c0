// Pair tests of two posed ObjectTrees: oriented-box separating axis tests
// (Gottschalk, Lin, Manocha: "OBBTree", SIGGRAPH 1996) in a descent that
// splits the larger box and visits the nearest children first, with the 15
// axis projections of a box pair carried down and updated incrementally.
// The plain reference descent lives at the end of this file.
#include "octbake/collide.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>

namespace octbake {
namespace {

constexpr int kMaxDepth = 12;  // deepest level a baked file may hold
// Every box half extent grows by kRelPad times the pair's coordinate magnitude
// in A's frame (both trees' local coordinates and their offset). Rounding in
// the relative transform and the SAT sums is ~1e-15 of that magnitude, so this
// leaves a wide margin, yet stays far below a depth-12 leaf (2^-12 of a root).
constexpr double kRelPad = 1e-9;
// Added to |R| (Gottschalk's guard): near-parallel edge pairs give near-zero
// cross axes on which both sides of the SAT inequality are pure rounding.
constexpr double kAxisPad = 1e-9;

using Coord = std::array<uint16_t, 3>;

BoxCoord to_coord(const Coord& c) { return {c[0], c[1], c[2]}; }
Coord from_coord(const BoxCoord& c) { return {uint16_t(c.x), uint16_t(c.y), uint16_t(c.z)}; }
Eigen::Vector3d cell_center(const Coord& c) { return {c[0] + 0.5, c[1] + 0.5, c[2] + 0.5}; }

// A total order on placed trees, by content first so that results (and box
// test counts) do not depend on argument order or on allocation addresses.
bool goes_first(const PlacedTree& a, const PlacedTree& b) {
  auto key = [](const PlacedTree& p) {
    const Aabb& r = p.tree->bounds();
    const auto& q = p.pose.rotation.coeffs();
    return std::array<double, 18>{r.min.x(), r.min.y(), r.min.z(), r.max.x(), r.max.y(), r.max.z(),
                                  double(p.tree->loaded_depth()), double(p.depth), p.pose.scale,
                                  p.pose.position.x(), p.pose.position.y(), p.pose.position.z(),
                                  q.x(), q.y(), q.z(), q.w(), 0, 0};
  };
  const auto ka = key(a), kb = key(b);
  if (ka != kb) return ka < kb;
  return !std::less<const ObjectTree*>{}(b.tree, a.tree);
}

void check(const PlacedTree& p) {
  assert(p.tree != nullptr);
  assert(p.depth >= 0 && p.depth <= p.tree->loaded_depth() && p.depth <= kMaxDepth);
  assert(std::isfinite(p.pose.scale) && p.pose.scale > 0);
  assert(p.pose.position.allFinite() && std::abs(p.pose.rotation.norm() - 1) < 1e-6);
  (void)p;
}

// The relative placement shared by both descents: q_A = t + s R q_B in A's
// local (unscaled) frame, and the padding of every box.
struct Relative {
  Eigen::Matrix3d r, sr, abs_r;  // abs_r = |R| + kAxisPad
  Eigen::Vector3d t;
  double s = 1, pad = 0;

  Relative(const PlacedTree& a, const PlacedTree& b) {
    const Eigen::Matrix3d ra = a.pose.rotation.toRotationMatrix();
    const Eigen::Matrix3d rb = b.pose.rotation.toRotationMatrix();
    s = b.pose.scale / a.pose.scale;
    // Subtract first: equal world offsets (1e7) cancel before any product.
    const Eigen::Vector3d dp = b.pose.position - a.pose.position;
    r = ra.transpose() * rb;
    sr = s * r;
    t = ra.transpose() * dp / a.pose.scale;
    abs_r = r.cwiseAbs().array() + kAxisPad;
    const Aabb& ba = a.tree->bounds();
    const Aabb& bb = b.tree->bounds();
    const double mag_a = std::max(ba.min.cwiseAbs().maxCoeff(), ba.max.cwiseAbs().maxCoeff());
    const double mag_b = std::max(bb.min.cwiseAbs().maxCoeff(), bb.max.cwiseAbs().maxCoeff());
    pad = kRelPad * (mag_a + s * mag_b + t.cwiseAbs().maxCoeff());
  }
};

// Is box c at depth d occupied in the tree?
bool occupied(const ObjectTree& tree, int depth, const BoxCoord& c) {
  const uint32_t end = 1u << depth;
  if (depth > tree.loaded_depth() || c.x >= end || c.y >= end || c.z >= end) return false;
  uint32_t index = 0;
  for (int d = 0; d < depth; ++d) {
    const int shift = depth - 1 - d;
    const uint32_t octant = ((c.x >> shift) & 1u) | (((c.y >> shift) & 1u) << 1) | (((c.z >> shift) & 1u) << 2);
    const uint8_t mask = tree.mask(d, index);
    if (!(mask & (1u << octant))) return false;
    index = tree.first_child(d, index) + uint32_t(std::popcount(unsigned(mask & ((1u << octant) - 1))));
  }
  return true;
}

// ---- The box-test kernel ---------------------------------------------------
// A box pair is described by its 15 separating axis projections of the centre
// offset (B's centre minus A's, in A's frame), lanes in this order: A's faces
// 0..2, B's faces 3..5, edge pairs A_i x B_j at 6 + 3i + j, lane 15 idle
// (always 0 against radius 0). The pair is separated iff some |p_k| > r_k.
constexpr int kLanes = 16;
using Lanes = double[kLanes];

using v4d = double __attribute__((vector_size(32)));
using v4m = decltype(v4d{} < v4d{});  // lane masks from comparisons

// By reference: a vector return value would make the ABI depend on -mavx.
[[gnu::always_inline]] inline void load4(v4d& v, const double* p) { std::memcpy(&v, p, sizeof v); }

// Children `octant[0..n)` of the split box against the other box: child c's
// projections are parent + offset[octant[c]], written to out[c]; bit c of the
// result is set iff child c overlaps. Radii: ra + rb lane by lane.
[[gnu::always_inline]] inline uint32_t children_overlap(const double* parent, const double* ra, const double* rb,
                                                        const Lanes* offset, const uint8_t* octant, int n,
                                                        Lanes* out) {
  v4d p[4], r[4];
  for (int k = 0; k < 4; ++k) {
    v4d rb_k;
    load4(p[k], parent + 4 * k);
    load4(r[k], ra + 4 * k);
    load4(rb_k, rb + 4 * k);
    r[k] += rb_k;
  }
  constexpr int64_t kNotSign = INT64_MAX;  // every bit but the sign: |x| in one AND
  const v4m not_sign = {kNotSign, kNotSign, kNotSign, kNotSign};
  uint32_t overlapping = 0;
  for (int c = 0; c < n; ++c) {
    const double* o = offset[octant[c]];
    v4m separated{};
    for (int k = 0; k < 4; ++k) {
      v4d q;
      load4(q, o + 4 * k);
      q += p[k];
      std::memcpy(out[c] + 4 * k, &q, sizeof q);
      const v4d abs_q = v4d(v4m(q) & not_sign);
      separated |= abs_q > r[k];
    }
    overlapping |= uint32_t((separated[0] | separated[1] | separated[2] | separated[3]) == 0) << c;
  }
  return overlapping;
}

uint32_t children_overlap_portable(const double* parent, const double* ra, const double* rb, const Lanes* offset,
                                   const uint8_t* octant, int n, Lanes* out) {
  return children_overlap(parent, ra, rb, offset, octant, n, out);
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
[[gnu::target("avx2")]] uint32_t children_overlap_avx2(const double* parent, const double* ra, const double* rb,
                                                       const Lanes* offset, const uint8_t* octant, int n,
                                                       Lanes* out) {
  return children_overlap(parent, ra, rb, offset, octant, n, out);
}
bool cpu_has_avx2() { return __builtin_cpu_supports("avx2"); }
#else
uint32_t children_overlap_avx2(const double* parent, const double* ra, const double* rb, const Lanes* offset,
                               const uint8_t* octant, int n, Lanes* out) {
  return children_overlap(parent, ra, rb, offset, octant, n, out);
}
bool cpu_has_avx2() { return false; }
#endif

std::atomic<bool> force_portable{false};

using Kernel = uint32_t (*)(const double*, const double*, const double*, const Lanes*, const uint8_t*, int, Lanes*);
Kernel pick_kernel() {
  static const bool avx2 = cpu_has_avx2();
  return avx2 && !force_portable.load(std::memory_order_relaxed) ? children_overlap_avx2 : children_overlap_portable;
}

// ---- The pair frame --------------------------------------------------------
// Per pair: the projection matrix W (p = W t), and per depth and tree, lazily,
// the 16-lane radii and the 8 child offsets of the projections.
class PairFrame {
 public:
  PairFrame(const PlacedTree& a, const PlacedTree& b) : rel_(a, b), depth_a_(a.depth), depth_b_(b.depth) {
    const Eigen::Matrix3d& r = rel_.r;
    const Eigen::Matrix3d& ar = rel_.abs_r;
    // w_[m][k]: weight of t_m in projection k; radius weights of A's and B's
    // half extents (Gottschalk's formulas, with |R| padded).
    for (auto* table : {&w_, &abs_wa_, &abs_wb_})
      for (auto& row : *table) std::fill(std::begin(row), std::end(row), 0.0);
    for (int i = 0; i < 3; ++i) {
      w_[i][i] = 1;
      abs_wa_[i][i] = 1;
      for (int j = 0; j < 3; ++j) {
        w_[i][3 + j] = r(i, j);
        abs_wa_[i][3 + j] = ar(i, j);
        abs_wb_[j][i] = ar(i, j);
      }
      abs_wb_[i][3 + i] = 1;
      const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
      for (int j = 0; j < 3; ++j) {
        const int k = 6 + 3 * i + j, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
        w_[i2][k] = r(i1, j);
        w_[i1][k] = -r(i2, j);
        abs_wa_[i1][k] = ar(i2, j);
        abs_wa_[i2][k] = ar(i1, j);
        abs_wb_[j1][k] = ar(i, j2);
        abs_wb_[j2][k] = ar(i, j1);
      }
    }
    // B's local axis j moves its centre by sR e_j in A's frame.
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < kLanes; ++k)
        wb_[j][k] = (w_[0][k] * rel_.sr(0, j) + w_[1][k] * rel_.sr(1, j)) + w_[2][k] * rel_.sr(2, j);

    const Aabb& ba = a.tree->bounds();
    const Aabb& bb = b.tree->bounds();
    a_min_ = ba.min;
    b_min_ = bb.min;
    for (int d = 0; d <= a.depth; ++d) {
      a_size_[d] = (ba.max - ba.min) / double(1u << d);
      size_a_[d] = (0.5 * a_size_[d]).squaredNorm();
    }
    for (int d = 0; d <= b.depth; ++d) {
      b_size_[d] = (bb.max - bb.min) / double(1u << d);
      size_b_[d] = (0.5 * rel_.s * b_size_[d]).squaredNorm();
    }
    ready_a_.fill(false);
    ready_b_.fill(false);
  }

  // Split A rather than B at depths (da, db)? The larger box splits.
  bool split_a(int da, int db) const {
    if (da == depth_a_) return false;
    if (db == depth_b_) return true;
    return size_a_[da] >= size_b_[db];
  }

  // Projections of box pair (A's ca at da, B's cb at db).
  void project(const Coord& ca, int da, const Coord& cb, int db, Lanes& p) const {
    const Eigen::Vector3d qa = a_min_ + a_size_[da].cwiseProduct(cell_center(ca));
    const Eigen::Vector3d qb = b_min_ + b_size_[db].cwiseProduct(cell_center(cb));
    const Eigen::Vector3d t = (rel_.t + rel_.sr * qb) - qa;
    for (int k = 0; k < kLanes; ++k) p[k] = (w_[0][k] * t[0] + w_[1][k] * t[1]) + w_[2][k] * t[2];
  }

  bool overlap(const Lanes& p, int da, int db) {
    const double* ra = radius_a(da);
    const double* rb = radius_b(db);
    bool separated = false;
    for (int k = 0; k < kLanes; ++k) separated |= std::abs(p[k]) > ra[k] + rb[k];
    return !separated;
  }

  const double* radius_a(int d) { return level_a(d).radius; }
  const double* radius_b(int d) { return level_b(d).radius; }
  // Offsets of the 8 children at depth d >= 1 (octant order).
  const Lanes* offsets_a(int d) { return level_a(d).offset; }
  const Lanes* offsets_b(int d) { return level_b(d).offset; }

 private:
  struct Level {
    Lanes radius;
    Lanes offset[8];
  };

  // A child at depth d sits at its parent's centre +- half its own size on
  // each axis of its tree; q is that half size, weights its effect on p.
  static void fill_offsets(Level& level, const Lanes (&weights)[3], const Eigen::Vector3d& q, double sign) {
    Lanes e[3];
    for (int m = 0; m < 3; ++m)
      for (int k = 0; k < kLanes; ++k) e[m][k] = sign * weights[m][k] * q[m];
    for (int oct = 0; oct < 8; ++oct)
      for (int k = 0; k < kLanes; ++k)
        level.offset[oct][k] = ((oct & 1 ? e[0][k] : -e[0][k]) + (oct & 2 ? e[1][k] : -e[1][k])) +
                               (oct & 4 ? e[2][k] : -e[2][k]);
  }

  static void fill_radius(Level& level, const Lanes (&weights)[3], const Eigen::Vector3d& half) {
    for (int k = 0; k < kLanes; ++k)
      level.radius[k] = (weights[0][k] * half[0] + weights[1][k] * half[1]) + weights[2][k] * half[2];
  }

  const Level& level_a(int d) {
    assert(d <= depth_a_);
    if (!ready_a_[d]) {
      fill_radius(levels_a_[d], abs_wa_, ((0.5 * a_size_[d]).array() + rel_.pad).matrix());
      // t = centre B - centre A: A's child moving by +q moves t by -q.
      if (d > 0) fill_offsets(levels_a_[d], w_, 0.5 * a_size_[d], -1.0);
      ready_a_[d] = true;
    }
    return levels_a_[d];
  }

  const Level& level_b(int d) {
    assert(d <= depth_b_);
    if (!ready_b_[d]) {
      fill_radius(levels_b_[d], abs_wb_, ((0.5 * rel_.s * b_size_[d]).array() + rel_.pad).matrix());
      if (d > 0) fill_offsets(levels_b_[d], wb_, 0.5 * b_size_[d], 1.0);
      ready_b_[d] = true;
    }
    return levels_b_[d];
  }

  Relative rel_;
  int depth_a_, depth_b_;
  Lanes w_[3], wb_[3], abs_wa_[3], abs_wb_[3];
  Eigen::Vector3d a_min_, b_min_;
  std::array<Eigen::Vector3d, kMaxDepth + 1> a_size_, b_size_;
  std::array<double, kMaxDepth + 1> size_a_{}, size_b_{};
  std::array<bool, kMaxDepth + 1> ready_a_, ready_b_;
  std::array<Level, kMaxDepth + 1> levels_a_, levels_b_;
};

// A box pair known to overlap, waiting on the descent stack.
struct Entry {
  alignas(32) Lanes p;
  uint32_t ia, ib;  // level indices
  Coord ca, cb;
  uint8_t da, db;
};

// DFS stack bound: an expansion pushes <= 8 pairs and a path has at most
// da + db <= 2 * kMaxDepth expansions, each leaving its pushes on the stack.
constexpr size_t kStackSize = 8 * 2 * kMaxDepth + 1;

// Depth-first descent of an overlapping root pair (canonical order);
// on_leaf(entry) returns true to stop.
template <class OnLeaf>
void descend(PairFrame& frame, const PlacedTree& a, const PlacedTree& b, PairTest& result, OnLeaf on_leaf) {
  const Kernel kernel = pick_kernel();
  std::array<Entry, kStackSize> stack;
  size_t n = 0;
  {
    Entry& root = stack[n];
    root.ia = root.ib = 0;
    root.ca = root.cb = {0, 0, 0};
    root.da = root.db = 0;
    frame.project(root.ca, 0, root.cb, 0, root.p);
    ++result.box_tests;
    if (!frame.overlap(root.p, 0, 0)) return;
    ++n;
  }
  alignas(32) Lanes out[8];
  while (n > 0) {
    const Entry& e = stack[--n];
    const bool split_a = frame.split_a(e.da, e.db);
    if (!split_a && e.db == b.depth) {  // neither can split: a leaf pair
      result.hit = true;
      if (on_leaf(e)) return;
      continue;
    }
    // Copy what the pushes below would overwrite.
    const uint32_t ia = e.ia, ib = e.ib;
    const Coord ca = e.ca, cb = e.cb;
    const int da = e.da, db = e.db;
    const ObjectTree& tree = split_a ? *a.tree : *b.tree;
    const int d = split_a ? da : db;
    const uint32_t index = split_a ? ia : ib;
    const uint8_t mask = tree.mask(d, index);
    const uint32_t first = tree.first_child(d, index);
    uint8_t octant[8];
    int count = 0;
    for (uint8_t j = 0; j < 8; ++j)
      if (mask & (1u << j)) octant[count++] = j;
    const uint32_t hits =
        split_a ? kernel(e.p, frame.radius_a(d + 1), frame.radius_b(db), frame.offsets_a(d + 1), octant, count, out)
                : kernel(e.p, frame.radius_a(da), frame.radius_b(d + 1), frame.offsets_b(d + 1), octant, count, out);
    result.box_tests += uint64_t(count);
    if (hits == 0) continue;
    // Nearest first: sort the overlapping children by centre distance
    // (lanes 0..2 are the offset in A's axes), ties in octant order.
    int order[8];
    double key[8];
    int m = 0;
    for (int c = 0; c < count; ++c) {
      if (!(hits & (1u << c))) continue;
      const double k = (out[c][0] * out[c][0] + out[c][1] * out[c][1]) + out[c][2] * out[c][2];
      int at = m++;
      for (; at > 0 && key[at - 1] > k; --at) order[at] = order[at - 1], key[at] = key[at - 1];
      order[at] = c, key[at] = k;
    }
    assert(n + size_t(m) <= kStackSize);
    // Pushed farthest first so that the nearest is popped next.
    for (int s = m - 1; s >= 0; --s) {
      const int c = order[s];
      const uint8_t j = octant[c];
      Entry& child = stack[n++];
      std::memcpy(child.p, out[c], sizeof(Lanes));
      const Coord grown = split_a ? ca : cb;
      const Coord coord{uint16_t(2 * grown[0] + (j & 1u)), uint16_t(2 * grown[1] + ((j >> 1) & 1u)),
                        uint16_t(2 * grown[2] + ((j >> 2) & 1u))};
      child.ia = split_a ? first + uint32_t(c) : ia;
      child.ib = split_a ? ib : first + uint32_t(c);
      child.ca = split_a ? coord : ca;
      child.cb = split_a ? cb : coord;
      child.da = uint8_t(split_a ? da + 1 : da);
      child.db = uint8_t(split_a ? db : db + 1);
    }
  }
}

// The pair in canonical order, the leaf pair mapped back on the way out.
struct Canonical {
  const PlacedTree& first;
  const PlacedTree& second;
  bool swapped;
  Canonical(const PlacedTree& a, const PlacedTree& b)
      : first(goes_first(a, b) ? a : b), second(goes_first(a, b) ? b : a), swapped(!goes_first(a, b)) {}
  LeafPair to_caller(const Coord& c1, const Coord& c2) const {
    return swapped ? LeafPair{to_coord(c2), to_coord(c1)} : LeafPair{to_coord(c1), to_coord(c2)};
  }
};

// collide() with an optional leaf pair (in the caller's order) to try first.
PairTest collide_with_hint(const PlacedTree& a, const PlacedTree& b, const LeafPair* hint) {
  check(a);
  check(b);
  const Canonical pair(a, b);
  PairFrame frame(pair.first, pair.second);
  PairTest result;
  if (hint) {
    const Coord c1 = from_coord(pair.swapped ? hint->b : hint->a), c2 = from_coord(pair.swapped ? hint->a : hint->b);
    Lanes p;
    frame.project(c1, pair.first.depth, c2, pair.second.depth, p);
    ++result.box_tests;
    if (frame.overlap(p, pair.first.depth, pair.second.depth)) {
      result.hit = true;
      result.leaf = *hint;
      return result;
    }
  }
  descend(frame, pair.first, pair.second, result, [&](const Entry& e) {
    result.leaf = pair.to_caller(e.ca, e.cb);
    return true;
  });
  return result;
}

}  // namespace

void use_portable_box_kernel(bool on) { force_portable.store(on, std::memory_order_relaxed); }

PairTest collide(const PlacedTree& a, const PlacedTree& b) { return collide_with_hint(a, b, nullptr); }

PairTest collide(const PlacedTree& a, const PlacedTree& b, PairCache& cache) {
  const bool usable = cache.tree_a != nullptr && cache.tree_a == a.tree && cache.tree_b == b.tree &&
                      cache.depth_a == a.depth && cache.depth_b == b.depth &&
                      occupied(*a.tree, a.depth, cache.leaf.a) && occupied(*b.tree, b.depth, cache.leaf.b);
  const PairTest result = collide_with_hint(a, b, usable ? &cache.leaf : nullptr);
  cache = result.hit ? PairCache{a.tree, b.tree, a.depth, b.depth, result.leaf} : PairCache{};
  return result;
}

OrientedBox leaf_box(const PlacedTree& p, const BoxCoord& c) {
  return place(p.tree->masks().box_bounds(p.depth, c), p.pose);
}

PairTest collide_all(const PlacedTree& a, const PlacedTree& b, std::vector<LeafPair>& out) {
  check(a);
  check(b);
  const Canonical pair(a, b);
  PairFrame frame(pair.first, pair.second);
  PairTest result;
  descend(frame, pair.first, pair.second, result, [&](const Entry& e) {
    out.push_back(pair.to_caller(e.ca, e.cb));
    return false;
  });
  return result;
}

// ---- Reference descent -----------------------------------------------------
// Both trees split at once, child pairs in octant order, one scalar 15-axis
// test per box pair computed from the two centres.
namespace {
namespace reference {

// DFS stack bound: an expansion pushes <= 64 pairs when both trees descend and
// <= 8 when one does; a path holds at most min(da, db) of the first kind and
// |da - db| of the second, each leaving its pushes on the stack.
constexpr size_t kStackSize = 64 * kMaxDepth;

struct Entry {
  uint32_t ia, ib;
  Coord ca, cb;
  uint8_t da, db;
};

struct Child {
  uint32_t index;
  Coord coord;
};

// Occupied children of box (d, i, c), in octant order.
int children(const ObjectTree& tree, int d, uint32_t i, const Coord& c, Child* out) {
  const uint8_t mask = tree.mask(d, i);
  uint32_t next = tree.first_child(d, i);
  int n = 0;
  for (uint32_t j = 0; j < 8; ++j) {
    if (!(mask & (1u << j))) continue;
    out[n++] = {next++,
                {uint16_t(2 * c[0] + (j & 1u)), uint16_t(2 * c[1] + ((j >> 1) & 1u)),
                 uint16_t(2 * c[2] + ((j >> 2) & 1u))}};
  }
  return n;
}

// B's boxes in A's frame with per-depth radii: a box test is two centres and
// 15 comparisons.
class PairFrame {
 public:
  PairFrame(const PlacedTree& a, const PlacedTree& b) : rel_(a, b) {
    const Eigen::Matrix3d& abs_r = rel_.abs_r;
    const Aabb& ba = a.tree->bounds();
    const Aabb& bb = b.tree->bounds();
    a_min_ = ba.min;
    b_min_ = bb.min;
    for (int d = 0; d <= a.depth; ++d) {
      a_size_[d] = (ba.max - ba.min) / double(1u << d);
      a_half_[d] = (0.5 * a_size_[d]).array() + rel_.pad;
      rad_a_[d] = abs_r.transpose() * a_half_[d];
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          cross_a_[d][3 * i + j] = a_half_[d][(i + 1) % 3] * abs_r((i + 2) % 3, j) +
                                   a_half_[d][(i + 2) % 3] * abs_r((i + 1) % 3, j);
    }
    for (int d = 0; d <= b.depth; ++d) {
      b_size_[d] = (bb.max - bb.min) / double(1u << d);
      b_half_[d] = (0.5 * rel_.s * b_size_[d]).array() + rel_.pad;
      rad_b_[d] = abs_r * b_half_[d];
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          cross_b_[d][3 * i + j] = b_half_[d][(j + 1) % 3] * abs_r(i, (j + 2) % 3) +
                                   b_half_[d][(j + 2) % 3] * abs_r(i, (j + 1) % 3);
    }
  }

  bool overlap(const Entry& e) const {
    const Eigen::Matrix3d& r = rel_.r;
    const Eigen::Vector3d ca = a_min_ + a_size_[e.da].cwiseProduct(cell_center(e.ca));
    const Eigen::Vector3d qb = b_min_ + b_size_[e.db].cwiseProduct(cell_center(e.cb));
    const Eigen::Vector3d t = (rel_.t + rel_.sr * qb) - ca;  // B's centre relative to A's
    const Eigen::Vector3d& ah = a_half_[e.da];
    const Eigen::Vector3d& bh = b_half_[e.db];
    for (int i = 0; i < 3; ++i)  // A's face normals
      if (std::abs(t[i]) > ah[i] + rad_b_[e.db][i]) return false;
    const Eigen::Vector3d u = r.transpose() * t;
    for (int j = 0; j < 3; ++j)  // B's face normals
      if (std::abs(u[j]) > rad_a_[e.da][j] + bh[j]) return false;
    const auto& xa = cross_a_[e.da];
    const auto& xb = cross_b_[e.db];
    for (int i = 0; i < 3; ++i) {  // edge-edge axes A_i x B_j
      const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
      for (int j = 0; j < 3; ++j) {
        const double lhs = std::abs(t[i2] * r(i1, j) - t[i1] * r(i2, j));
        if (lhs > xa[3 * i + j] + xb[3 * i + j]) return false;
      }
    }
    return true;
  }

 private:
  Relative rel_;
  Eigen::Vector3d a_min_, b_min_;
  std::array<Eigen::Vector3d, kMaxDepth + 1> a_size_, b_size_, a_half_, b_half_, rad_a_, rad_b_;
  std::array<std::array<double, 9>, kMaxDepth + 1> cross_a_, cross_b_;
};

template <class OnLeaf>
PairTest descend(const PlacedTree& a, const PlacedTree& b, OnLeaf on_leaf) {
  check(a);
  check(b);
  const PairFrame frame(a, b);
  PairTest result;
  std::array<Entry, kStackSize> stack;
  size_t n = 0;
  stack[n++] = Entry{0, 0, {0, 0, 0}, {0, 0, 0}, 0, 0};
  while (n > 0) {
    const Entry e = stack[--n];
    ++result.box_tests;
    if (!frame.overlap(e)) continue;
    const bool grow_a = e.da < a.depth, grow_b = e.db < b.depth;
    if (!grow_a && !grow_b) {
      result.hit = true;
      if (on_leaf(e)) return result;
      continue;
    }
    // A tree already at its depth takes part with its own box.
    Child ka[8], kb[8];
    const int na = grow_a ? children(*a.tree, e.da, e.ia, e.ca, ka) : (ka[0] = {e.ia, e.ca}, 1);
    const int nb = grow_b ? children(*b.tree, e.db, e.ib, e.cb, kb) : (kb[0] = {e.ib, e.cb}, 1);
    assert(n + size_t(na * nb) <= kStackSize);
    const uint8_t da = uint8_t(e.da + grow_a), db = uint8_t(e.db + grow_b);
    // Pushed in reverse so that the first child pair is tested first.
    for (int i = na - 1; i >= 0; --i)
      for (int j = nb - 1; j >= 0; --j) stack[n++] = Entry{ka[i].index, kb[j].index, ka[i].coord, kb[j].coord, da, db};
  }
  return result;
}

template <class OnLeaf>
PairTest run(const PlacedTree& a, const PlacedTree& b, OnLeaf on_leaf) {
  const Canonical pair(a, b);
  return descend(pair.first, pair.second, [&](const Entry& e) { return on_leaf(pair.to_caller(e.ca, e.cb)); });
}

}  // namespace reference
}  // namespace

PairTest collide_reference(const PlacedTree& a, const PlacedTree& b) {
  LeafPair found;
  PairTest t = reference::run(a, b, [&](const LeafPair& leaf) {
    found = leaf;
    return true;
  });
  t.leaf = found;
  return t;
}

PairTest collide_all_reference(const PlacedTree& a, const PlacedTree& b, std::vector<LeafPair>& out) {
  return reference::run(a, b, [&](const LeafPair& leaf) {
    out.push_back(leaf);
    return false;
  });
}

}  // namespace octbake
