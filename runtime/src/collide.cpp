// Simultaneous descent of two posed ObjectTrees with an oriented-box
// separating axis test (Gottschalk, Lin, Manocha: "OBBTree", SIGGRAPH 1996).
#include "octbake/collide.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
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
// DFS stack bound: an expansion pushes <= 64 pairs when both trees descend and
// <= 8 when one does; a path holds at most min(da, db) of the first kind and
// |da - db| of the second, each leaving its pushes on the stack.
constexpr size_t kStackSize = 64 * kMaxDepth;

// A box pair on the descent stack: level indices, integer coordinates, depths.
struct Entry {
  uint32_t ia, ib;
  std::array<uint16_t, 3> ca, cb;
  uint8_t da, db;
};

struct Child {
  uint32_t index;
  std::array<uint16_t, 3> coord;
};

// Occupied children of box (d, i, c), in octant order.
int children(const ObjectTree& tree, int d, uint32_t i, const std::array<uint16_t, 3>& c, Child* out) {
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

Eigen::Vector3d cell_center(const std::array<uint16_t, 3>& c) { return {c[0] + 0.5, c[1] + 0.5, c[2] + 0.5}; }

// B's boxes in A's local (unscaled) frame: q_A = t + s R q_B, with per-depth
// radii precomputed so that a box test is two centres and 15 comparisons.
class PairFrame {
 public:
  PairFrame(const PlacedTree& a, const PlacedTree& b) {
    const Eigen::Matrix3d ra = a.pose.rotation.toRotationMatrix();
    const Eigen::Matrix3d rb = b.pose.rotation.toRotationMatrix();
    const double s = b.pose.scale / a.pose.scale;
    // Subtract first: equal world offsets (1e7) cancel before any product.
    const Eigen::Vector3d dp = b.pose.position - a.pose.position;
    r_ = ra.transpose() * rb;
    sr_ = s * r_;
    t_ = ra.transpose() * dp / a.pose.scale;
    const Eigen::Matrix3d abs_r = r_.cwiseAbs().array() + kAxisPad;

    const Aabb& ba = a.tree->bounds();
    const Aabb& bb = b.tree->bounds();
    const double mag_a = std::max(ba.min.cwiseAbs().maxCoeff(), ba.max.cwiseAbs().maxCoeff());
    const double mag_b = std::max(bb.min.cwiseAbs().maxCoeff(), bb.max.cwiseAbs().maxCoeff());
    const double pad = kRelPad * (mag_a + s * mag_b + t_.cwiseAbs().maxCoeff());
    a_min_ = ba.min;
    b_min_ = bb.min;
    for (int d = 0; d <= a.depth; ++d) {
      a_size_[d] = (ba.max - ba.min) / double(1u << d);
      a_half_[d] = (0.5 * a_size_[d]).array() + pad;
      rad_a_[d] = abs_r.transpose() * a_half_[d];
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          cross_a_[d][3 * i + j] = a_half_[d][(i + 1) % 3] * abs_r((i + 2) % 3, j) +
                                   a_half_[d][(i + 2) % 3] * abs_r((i + 1) % 3, j);
    }
    for (int d = 0; d <= b.depth; ++d) {
      b_size_[d] = (bb.max - bb.min) / double(1u << d);
      b_half_[d] = (0.5 * s * b_size_[d]).array() + pad;
      rad_b_[d] = abs_r * b_half_[d];
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          cross_b_[d][3 * i + j] = b_half_[d][(j + 1) % 3] * abs_r(i, (j + 2) % 3) +
                                   b_half_[d][(j + 2) % 3] * abs_r(i, (j + 1) % 3);
    }
  }

  bool overlap(const Entry& e) const {
    const Eigen::Vector3d ca = a_min_ + a_size_[e.da].cwiseProduct(cell_center(e.ca));
    const Eigen::Vector3d qb = b_min_ + b_size_[e.db].cwiseProduct(cell_center(e.cb));
    const Eigen::Vector3d t = (t_ + sr_ * qb) - ca;  // B's centre relative to A's
    const Eigen::Vector3d& ah = a_half_[e.da];
    const Eigen::Vector3d& bh = b_half_[e.db];
    // A's face normals.
    for (int i = 0; i < 3; ++i)
      if (std::abs(t[i]) > ah[i] + rad_b_[e.db][i]) return false;
    // B's face normals.
    const Eigen::Vector3d u = r_.transpose() * t;
    for (int j = 0; j < 3; ++j)
      if (std::abs(u[j]) > rad_a_[e.da][j] + bh[j]) return false;
    // Edge-edge axes A_i x B_j.
    const auto& xa = cross_a_[e.da];
    const auto& xb = cross_b_[e.db];
    for (int i = 0; i < 3; ++i) {
      const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
      for (int j = 0; j < 3; ++j) {
        const double lhs = std::abs(t[i2] * r_(i1, j) - t[i1] * r_(i2, j));
        if (lhs > xa[3 * i + j] + xb[3 * i + j]) return false;
      }
    }
    return true;
  }

 private:
  Eigen::Matrix3d r_, sr_;
  Eigen::Vector3d t_, a_min_, b_min_;
  std::array<Eigen::Vector3d, kMaxDepth + 1> a_size_, b_size_, a_half_, b_half_, rad_a_, rad_b_;
  std::array<std::array<double, 9>, kMaxDepth + 1> cross_a_, cross_b_;
};

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

// Depth-first descent in canonical order; on_leaf(entry) returns true to stop.
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

BoxCoord to_coord(const std::array<uint16_t, 3>& c) { return {c[0], c[1], c[2]}; }

}  // namespace

PairTest collide(const PlacedTree& a, const PlacedTree& b) {
  LeafPair found;
  if (goes_first(a, b)) {
    PairTest t = descend(a, b, [&](const Entry& e) {
      found = {to_coord(e.ca), to_coord(e.cb)};
      return true;
    });
    t.leaf = found;
    return t;
  }
  PairTest t = descend(b, a, [&](const Entry& e) {
    found = {to_coord(e.cb), to_coord(e.ca)};
    return true;
  });
  t.leaf = found;
  return t;
}

OrientedBox leaf_box(const PlacedTree& p, const BoxCoord& c) {
  return place(p.tree->masks().box_bounds(p.depth, c), p.pose);
}

PairTest collide_all(const PlacedTree& a, const PlacedTree& b, std::vector<LeafPair>& out) {
  if (goes_first(a, b))
    return descend(a, b, [&](const Entry& e) {
      out.push_back({to_coord(e.ca), to_coord(e.cb)});
      return false;
    });
  return descend(b, a, [&](const Entry& e) {
    out.push_back({to_coord(e.cb), to_coord(e.ca)});
    return false;
  });
}

}  // namespace octbake
