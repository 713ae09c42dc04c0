// Pair tests of two posed ObjectTrees: oriented-box separating axis tests
// (Gottschalk, Lin, Manocha: "OBBTree", SIGGRAPH 1996) in a descent that
// splits the larger box and visits the nearest children first, with the 15
// axis projections of a box pair carried down and updated incrementally.
// The plain reference descent lives at the end of this file.
#include "octbake/collide.h"
#include "octbake/format.h"
#include "nearest_first.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <type_traits>
#include <vector>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace octbake {
namespace {

// Every box half extent grows by kRelPad times the pair's coordinate magnitude
// in A's frame (both trees' local coordinates and their offset). Rounding in
// the relative transform and the SAT sums is ~1e-15 of that magnitude, so this
// leaves a wide margin, yet stays far below a depth-12 leaf (2^-12 of a root).
constexpr double kRelPad = 1e-9;
// Added to |R| (Gottschalk's guard): near-parallel edge pairs give near-zero
// cross axes on which both sides of the SAT inequality are pure rounding.
constexpr double kAxisPad = 1e-9;
// The padding never falls below kMinPad, so that every radius is at least
// ~2^-930 (the cross axes' padding is kAxisPad times it). Why: the AVX2 and
// AVX-512 builds fuse p + o 2^-d into one rounding, the portable build
// rounds o 2^-d first.
// The product is exact unless it is subnormal, and then the two sums can
// differ only where |p| < 2^-967 (a rounding boundary within 2^-1075 of p +
// o 2^-d needs p's spacing below 2^-1020): such a value is never above a
// radius, and the nearest-first order takes it as 0 (kOrderFloor). So every
// build gives the same hits, counts and leaf pairs (tested down to offsets
// of 1e-320).
constexpr double kMinPad = 0x1p-900;
constexpr double kOrderFloor = 0x1p-967;

using Coord = std::array<uint16_t, 3>;

// 2^-d for every depth (a table: std::ldexp is a library call).
constexpr std::array<double, 2 * kMaxDepth + 1> kHalfPow = [] {
  std::array<double, 2 * kMaxDepth + 1> h{};
  double v = 1;
  for (double& x : h) x = v, v *= 0.5;
  return h;
}();

BoxCoord to_coord(const Coord& c) { return {c[0], c[1], c[2]}; }
Coord from_coord(const BoxCoord& c) { return {uint16_t(c.x), uint16_t(c.y), uint16_t(c.z)}; }
Eigen::Vector3d cell_center(const Coord& c) { return {c[0] + 0.5, c[1] + 0.5, c[2] + 0.5}; }

// A total order on placed trees, by content first so that results (and box
// test counts) do not depend on argument order or on allocation addresses:
// bounds, depths, scale, position, rotation, compared in turn (the first
// difference decides; two different trees usually differ in the first value).
bool goes_first(const PlacedTree& a, const PlacedTree& b) {
  const Aabb &ra = a.tree->bounds(), &rb = b.tree->bounds();
  for (int i = 0; i < 3; ++i)
    if (ra.min[i] != rb.min[i]) return ra.min[i] < rb.min[i];
  for (int i = 0; i < 3; ++i)
    if (ra.max[i] != rb.max[i]) return ra.max[i] < rb.max[i];
  if (a.tree->loaded_depth() != b.tree->loaded_depth()) return a.tree->loaded_depth() < b.tree->loaded_depth();
  if (a.depth != b.depth) return a.depth < b.depth;
  if (a.pose.scale != b.pose.scale) return a.pose.scale < b.pose.scale;
  for (int i = 0; i < 3; ++i)
    if (a.pose.position[i] != b.pose.position[i]) return a.pose.position[i] < b.pose.position[i];
  const auto &qa = a.pose.rotation.coeffs(), &qb = b.pose.rotation.coeffs();  // x, y, z, w
  for (int i = 0; i < 4; ++i)
    if (qa[i] != qb[i]) return qa[i] < qb[i];
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
    const Eigen::Matrix3d ra = rotation_matrix(a.pose.rotation);
    const Eigen::Matrix3d rb = rotation_matrix(b.pose.rotation);
    s = b.pose.scale / a.pose.scale;
    // Subtract first: equal world offsets (1e7) cancel before any product.
    const Eigen::Vector3d dp = b.pose.position - a.pose.position;
    // R = Ra^T Rb, t = Ra^T dp / scale, coefficient by coefficient (the sums
    // in Eigen's order): Eigen's vectorised products read the matrices back
    // as pairs just after they were written one value at a time, and waited
    // for the stores.
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        const double v = (ra(0, i) * rb(0, j) + ra(1, i) * rb(1, j)) + ra(2, i) * rb(2, j);
        r(i, j) = v;
        sr(i, j) = s * v;
        abs_r(i, j) = std::abs(v) + kAxisPad;
      }
      t[i] = ((ra(0, i) * dp[0] + ra(1, i) * dp[1]) + ra(2, i) * dp[2]) / a.pose.scale;
    }
    const Aabb& ba = a.tree->bounds();
    const Aabb& bb = b.tree->bounds();
    const double mag_a = max_abs_coordinate(ba);
    const double mag_b = max_abs_coordinate(bb);
    pad = std::max(kRelPad * (mag_a + s * mag_b + t.cwiseAbs().maxCoeff()), kMinPad);
  }
};

// Whether one of B's axes is one of A's exactly (R has an entry +-1 whose
// row and column are otherwise 0): two objects turned about the same axis,
// like upright objects that only yaw, or unrotated ones. Every edge axis
// A_i x B_j is then zero or parallel to a face axis (A_i = +-B_j: A_i x B_k
// is +-B's third axis, A_k x B_j A's, and A_k x B_l lies along A_i), so in
// exact arithmetic the six face axes separate every box pair that all
// fifteen do, and the kernel tests lanes 0..7 only (kFaceLanes; 0..5 in
// collide's portable build, kSharedAxisLanes): half the work per child or
// less. The lanes are padded differently (by ~1e-9 of the boxes' size), so
// near the boundary the face axes alone may keep a pair that an edge axis
// separated: a contact more, never a miss.
bool shares_axis(const Eigen::Matrix3d& r) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (std::abs(r(i, j)) == 1 && r(i, (j + 1) % 3) == 0 && r(i, (j + 2) % 3) == 0 && r((i + 1) % 3, j) == 0 &&
          r((i + 2) % 3, j) == 0)
        return true;
  return false;
}

// The occupied octants of every child mask, in order, and how many (also
// the portable build's popcount: in an x86-64 build without POPCNT,
// std::popcount is a library call).
struct OctantTable {
  uint8_t count[256];
  uint8_t octant[256][8];
  constexpr OctantTable() : count{}, octant{} {
    for (int m = 0; m < 256; ++m)
      for (int j = 0; j < 8; ++j)
        if (m & (1 << j)) octant[m][count[m]++] = uint8_t(j);
  }
};
constexpr OctantTable kOctants;

// Set bits of a child mask below bit j: the index of child j among its
// occupied siblings.
uint32_t siblings_below(uint32_t mask, int j) { return kOctants.count[mask & ((1u << j) - 1)]; }

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
    index = tree.first_child(d, index) + siblings_below(mask, int(octant));
  }
  return true;
}

// ---- The box-test kernel ---------------------------------------------------
// A box pair is described by its 15 separating axis projections of the centre
// offset (B's centre minus A's, in A's frame), lanes in this order: A's faces
// 0..2, B's faces 3..5, edge pairs A_i x B_j at 6 + 3i + j, lane 15 idle
// (always 0 against radius 0). The pair is separated iff some |p_k| > r_k.
//
// children_overlap<kScale, kTested>(parent, radius, offset, scale, octant,
// n): the children `octant[0..n)` of the split box against the other box,
// on lanes 0..kTested-1 (all 16, or the face lanes: see shares_axis). The
// projections of the child in octant j are parent + offset[j] * scale (scale
// a power of two, so the product is exact) if kScale, else parent +
// offset[j] (the offsets already scaled to the children's depth: the same
// bits); bit j of the result is set iff that child overlaps (radius: the two
// boxes' radii summed lane by lane). Nothing is stored: the descent
// recomputes the same sums for the children it visits.
//
// half_overlaps<h>(p, offset, radius): one child, projections p + offset, on
// lanes 8h..8h+7 only (collide_all tests the second half only for children
// that pass the first).
//
// Three builds: plain C++, AVX2 and AVX-512. Each lane is at most one
// multiplication by a power of two, one addition, one absolute value and one
// ordered comparison; the AVX2 and AVX-512 builds fuse the first two (one
// rounding: exact unless the product is subnormal, which kMinPad makes
// harmless), so all three give the same results.
//
// Each build is a class whose kernel is inlined into the whole pair test,
// which is compiled once per build and chosen once per pair (run_pair): no
// call through a pointer in the descent's inner loop.
constexpr int kLanes = 16;
constexpr int kFaceLanes = 8;  // lanes 0..7: the six face axes (and two edge axes), see shares_axis
using Lanes = double[kLanes];

// Written per chunk of W lanes with GCC/Clang vector types, loaded and stored
// through pointers only: the compiler then emits one vector operation per
// chunk for whatever ISA the caller is built for (left to the
// auto-vectoriser, these loops came out as shuffles). W is the build's native
// width (kStoreLanes): a vector wider than the ISA's registers times a scalar
// is built through the stack, element by element (GCC), which cost the old
// AVX2 build ~40% of a deep pair and the portable build up to 5x.
template <int W>
struct Chunk;
template <>
struct Chunk<2> {
  using type = double __attribute__((vector_size(16)));
  using mem = double __attribute__((vector_size(16), aligned(8), may_alias));
  using mask = int64_t __attribute__((vector_size(16)));
};
template <>
struct Chunk<4> {
  using type = double __attribute__((vector_size(32)));
  using mem = double __attribute__((vector_size(32), aligned(8), may_alias));
  using mask = int64_t __attribute__((vector_size(32)));
};
template <>
struct Chunk<8> {
  using type = double __attribute__((vector_size(64)));
  using mem = double __attribute__((vector_size(64), aligned(8), may_alias));
  using mask = int64_t __attribute__((vector_size(64)));
};
template <int W>
using Vec = typename Chunk<W>::type;
template <int W>
[[gnu::always_inline]] inline void load(Vec<W>& v, const double* p) {
  v = *reinterpret_cast<const typename Chunk<W>::mem*>(p);
}
template <int W>
[[gnu::always_inline]] inline void store(double* p, const Vec<W>& v) {
  *reinterpret_cast<typename Chunk<W>::mem*>(p) = v;
}
// The pair frame's lane groups and centre transposes are 4 lanes wide in the
// AVX builds (HalfPair below stands in for them in the portable build).
using v4d = Vec<4>;

// separated |= (|x| > r) lane by lane, for vectors of any width: |x| is x
// with its sign bit cleared (one AND; a vector cast keeps the bits), and an
// ordered comparison (NaN compares false).
template <int W>
[[gnu::always_inline]] inline void mark_exceeding(typename Chunk<W>::mask& separated, const Vec<W>& x,
                                                  const Vec<W>& r) {
  using M = typename Chunk<W>::mask;
  separated |= Vec<W>(M(x) & INT64_MAX) > r;
}
template <int W>
[[gnu::always_inline]] inline bool any_lane(const typename Chunk<W>::mask& m) {
  int64_t any = 0;
  for (int i = 0; i < W; ++i) any |= m[i];
  return any != 0;
}

struct Portable {
  // siblings_below, per build.
  static uint32_t bits_below(uint32_t mask, int j) { return siblings_below(mask, j); }

  // Width of the generic code's vectors (radii, projections, offsets): the
  // ISA's register width, 2 here (SSE2, and NEON on ARM), 4 in the AVX2
  // build, 8 in the AVX-512 build. Lanes the descent writes and the kernel
  // reads back soon after (a child's projections, a level's radii) are thus
  // stored as wide as the kernel loads them: a load spanning two narrower
  // stores is not forwarded from them, it waits for them to retire.
  static constexpr int kStoreLanes = 2;
  // The pair frame's set-up (projections, radii, offsets) fills only the
  // lanes the descent tests: at two lanes a register, a pair that shares an
  // axis (shares_axis) then fills 6 lanes of 16 (kSharedAxisLanes). The AVX
  // builds fill all 16 lanes in one or two more vector operations; narrowing
  // theirs too made rotated pairs 2-4% slower (session 34, code laid out anew).
  static constexpr bool kNarrowSetUp = true;
  // The lanes collide tests a pair that shares an axis on: 0..5, the six
  // face axes, in three 2-lane chunks (lanes 6 and 7 are edge axes, which
  // add nothing there; the AVX builds take 0..7, one or two whole chunks).
  static constexpr int kSharedAxisLanes = 6;
  using V = Vec<kStoreLanes>;
  using M = typename Chunk<kStoreLanes>::mask;

  template <bool kScale, int kTested>
  [[gnu::always_inline]] static uint32_t children_overlap(const double* parent, const double* radius,
                                                          const Lanes* offset, double scale, const uint8_t* octant,
                                                          int n) {
    constexpr int kChunks = kTested / kStoreLanes;
    V p[kChunks], r[kChunks];
    for (int k = 0; k < kChunks; ++k) {
      load<kStoreLanes>(p[k], parent + kStoreLanes * k);
      load<kStoreLanes>(r[k], radius + kStoreLanes * k);
    }
    uint32_t overlapping = 0;
    for (int c = 0; c < n; ++c) {
      const double* o = offset[octant[c]];
      M separated{};
      for (int k = 0; k < kChunks; ++k) {
        V ok;
        load<kStoreLanes>(ok, o + kStoreLanes * k);
        mark_exceeding<kStoreLanes>(separated, kScale ? p[k] + ok * scale : p[k] + ok, r[k]);
      }
      overlapping |= uint32_t(!any_lane<kStoreLanes>(separated)) << octant[c];
    }
    return overlapping;
  }

  // One child (projections p + offset) against radius on half kHalf of the
  // lanes, [8 kHalf, 8 kHalf + 8): separated on none of them? A child
  // overlaps iff it passes both halves.
  template <int kHalf>
  [[gnu::always_inline]] static bool half_overlaps(const double* p, const double* offset, const double* radius) {
    M separated{};
    for (int k = 8 * kHalf; k < 8 * kHalf + 8; k += kStoreLanes) {
      V x, y, r;
      load<kStoreLanes>(x, p + k);
      load<kStoreLanes>(y, offset + k);
      load<kStoreLanes>(r, radius + k);
      mark_exceeding<kStoreLanes>(separated, x + y, r);
    }
    return !any_lane<kStoreLanes>(separated);
  }

  // Is some lane of x at least y's (ordered)? PairFrame::least_separation's
  // early out, per build: the generic any_lane of a wide mask is built lane
  // by lane.
  [[gnu::always_inline]] static bool any_at_least(const V& x, const V& y) { return any_lane<kStoreLanes>(x >= y); }

  // out = a + b * scale, the first kTested lanes: a child's projections from
  // its parent's and its offset, as children_overlap computes them.
  template <int kTested>
  [[gnu::always_inline]] static void add_scaled(double* out, const double* a, const double* b, double scale) {
    for (int k = 0; k < kTested; k += kStoreLanes) {
      V x, y;
      load<kStoreLanes>(x, a + k);
      load<kStoreLanes>(y, b + k);
      store<kStoreLanes>(out + k, x + y * scale);
    }
  }
};

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define OCTBAKE_X86_KERNELS 1

// AVX2 with FMA (every AVX2 CPU has it; cpu_has checks both).
struct Avx2 {
  static constexpr int kStoreLanes = 4;
  static constexpr bool kNarrowSetUp = false;  // see Portable
  static constexpr int kSharedAxisLanes = kFaceLanes;

  // As Portable's, with the POPCNT instruction (a table lookup was 1-2%
  // slower here).
  [[gnu::target("avx2,popcnt")]] static uint32_t bits_below(uint32_t mask, int j) {
    return uint32_t(std::popcount(mask & ((1u << j) - 1)));
  }

  // By reference: AVX vectors passed by value from a caller built without
  // AVX change the ABI (clang refuses them).
  [[gnu::target("avx2")]] static bool any_at_least(const __m256d& x, const __m256d& y) {
    return _mm256_movemask_pd(_mm256_cmp_pd(x, y, _CMP_GE_OQ)) != 0;
  }

  // As Portable's, the products fused with the sums: the same results (see
  // kMinPad).
  template <int kTested>
  [[gnu::target("avx2,fma")]] static void add_scaled(double* out, const double* a, const double* b, double scale) {
    const __m256d s = _mm256_set1_pd(scale);
    for (int k = 0; k < kTested; k += 4)
      _mm256_storeu_pd(out + k, _mm256_fmadd_pd(_mm256_loadu_pd(b + k), s, _mm256_loadu_pd(a + k)));
  }
  template <bool kScale, int kTested>
  [[gnu::target("avx2,fma")]] static uint32_t children_overlap(const double* parent, const double* radius,
                                                         const Lanes* offset, double scale, const uint8_t* octant,
                                                         int n) {
    constexpr int kChunks = kTested / 4;
    const __m256d s = _mm256_set1_pd(scale);
    const __m256d not_sign = _mm256_castsi256_pd(_mm256_set1_epi64x(INT64_MAX));  // |x| is one AND
    __m256d p[kChunks], r[kChunks];
    for (int k = 0; k < kChunks; ++k) {
      p[k] = _mm256_loadu_pd(parent + 4 * k);
      r[k] = _mm256_loadu_pd(radius + 4 * k);
    }
    uint32_t overlapping = 0;
    for (int c = 0; c < n; ++c) {
      const double* o = offset[octant[c]];
      __m256d separated = _mm256_setzero_pd();
      for (int k = 0; k < kChunks; ++k) {
        const __m256d ok = _mm256_loadu_pd(o + 4 * k);
        const __m256d q = kScale ? _mm256_fmadd_pd(ok, s, p[k]) : _mm256_add_pd(p[k], ok);
        separated = _mm256_or_pd(separated, _mm256_cmp_pd(_mm256_and_pd(q, not_sign), r[k], _CMP_GT_OQ));
      }
      overlapping |= uint32_t(_mm256_testz_pd(separated, separated)) << octant[c];  // no sign bit set
    }
    return overlapping;
  }

  template <int kHalf>
  [[gnu::target("avx2")]] static bool half_overlaps(const double* p, const double* offset, const double* radius) {
    const __m256d not_sign = _mm256_castsi256_pd(_mm256_set1_epi64x(INT64_MAX));
    __m256d separated = _mm256_setzero_pd();
    for (int k = 8 * kHalf; k < 8 * kHalf + 8; k += 4) {
      const __m256d q = _mm256_add_pd(_mm256_loadu_pd(p + k), _mm256_loadu_pd(offset + k));
      const __m256d r = _mm256_loadu_pd(radius + k);
      separated = _mm256_or_pd(separated, _mm256_cmp_pd(_mm256_and_pd(q, not_sign), r, _CMP_GT_OQ));
    }
    return _mm256_testz_pd(separated, separated);
  }
};

struct Avx512 {
  static constexpr int kStoreLanes = 8;
  static constexpr bool kNarrowSetUp = false;  // see Portable
  static constexpr int kSharedAxisLanes = kFaceLanes;

  [[gnu::target("avx512f,popcnt")]] static uint32_t bits_below(uint32_t mask, int j) {
    return Avx2::bits_below(mask, j);
  }

  [[gnu::target("avx512f")]] static bool any_at_least(const __m512d& x, const __m512d& y) {
    return _mm512_cmp_pd_mask(x, y, _CMP_GE_OQ) != 0;
  }

  // As Portable's, the products fused with the sums: the same results (see
  // kMinPad).
  template <int kTested>
  [[gnu::target("avx512f")]] static void add_scaled(double* out, const double* a, const double* b, double scale) {
    const __m512d s = _mm512_set1_pd(scale);
    for (int k = 0; k < kTested; k += 8)
      _mm512_storeu_pd(out + k, _mm512_fmadd_pd(_mm512_loadu_pd(b + k), s, _mm512_loadu_pd(a + k)));
  }
  template <bool kScale, int kTested>
  [[gnu::target("avx512f")]] static uint32_t children_overlap(const double* parent, const double* radius,
                                                            const Lanes* offset, double scale,
                                                            const uint8_t* octant, int n) {
    const __m512d s = _mm512_set1_pd(scale);
    const __m512d p0 = _mm512_loadu_pd(parent), r0 = _mm512_loadu_pd(radius);
    if constexpr (kTested == 8) {
      uint32_t overlapping = 0;
      for (int c = 0; c < n; ++c) {
        const __m512d o0 = _mm512_loadu_pd(offset[octant[c]]);
        const __m512d q0 = kScale ? _mm512_fmadd_pd(o0, s, p0) : _mm512_add_pd(p0, o0);
        overlapping |= uint32_t(_mm512_cmp_pd_mask(_mm512_abs_pd(q0), r0, _CMP_GT_OQ) == 0) << octant[c];
      }
      return overlapping;
    } else {
      const __m512d p1 = _mm512_loadu_pd(parent + 8), r1 = _mm512_loadu_pd(radius + 8);
      uint32_t overlapping = 0;
      for (int c = 0; c < n; ++c) {
        const double* o = offset[octant[c]];
        const __m512d o0 = _mm512_loadu_pd(o), o1 = _mm512_loadu_pd(o + 8);
        const __m512d q0 = kScale ? _mm512_fmadd_pd(o0, s, p0) : _mm512_add_pd(p0, o0);
        const __m512d q1 = kScale ? _mm512_fmadd_pd(o1, s, p1) : _mm512_add_pd(p1, o1);
        const __mmask8 separated = __mmask8(_mm512_cmp_pd_mask(_mm512_abs_pd(q0), r0, _CMP_GT_OQ) |
                                            _mm512_cmp_pd_mask(_mm512_abs_pd(q1), r1, _CMP_GT_OQ));
        overlapping |= uint32_t(separated == 0) << octant[c];
      }
      return overlapping;
    }
  }

  template <int kHalf>
  [[gnu::target("avx512f")]] static bool half_overlaps(const double* p, const double* offset, const double* radius) {
    const int k = 8 * kHalf;
    const __m512d q = _mm512_add_pd(_mm512_loadu_pd(p + k), _mm512_loadu_pd(offset + k));
    return _mm512_cmp_pd_mask(_mm512_abs_pd(q), _mm512_loadu_pd(radius + k), _CMP_GT_OQ) == 0;
  }
};
#endif

// ---- Per-pair lane tables -------------------------------------------------
// Built per pair test from the relative placement, inside the pair test's
// build (so at its vector width); the same operations in the same order in
// every build, so every build gives the same bits.
struct LaneTables {
  // w[m][k]: weight of t_m in projection k (p = W t).
  alignas(64) Lanes w[3];
  // Offsets of the 8 children at depth 1, octant order, per tree (filled when
  // the tree first splits): at depth d they are these times 2^(1-d), exactly.
  alignas(64) Lanes offset_a[8], offset_b[8];
  // Radius of a padded box on every axis at depth d: base * 2^-d + padding.
  alignas(64) Lanes base_a, base_b, padding_a, padding_b;
};

// A child at depth 1 sits at the root's centre +- q on each axis m of its
// tree; weights[m] give the effect on the projections (times sign). Octants
// 7 - j are the negations of octants j (negation is exact).
// weights[m][c]: lanes W c..W c + W - 1 of axis m's weights. Only lanes
// 0..kFilled-1 are filled (the lanes the descent tests; see kSetUp).
template <int W, int kFilled>
[[gnu::always_inline]] inline void fill_offsets(Lanes* offset, const Vec<W> (*weights)[kLanes / W], const double* q,
                                                double sign) {
  const double f0 = sign * q[0], f1 = sign * q[1], f2 = sign * q[2];
  for (int c = 0; c < kFilled / W; ++c) {
    const Vec<W> e0 = weights[0][c] * f0, e1 = weights[1][c] * f1, e2 = weights[2][c] * f2;
    const Vec<W> s01 = e0 + e1, d01 = e0 - e1;  // +x+y, +x-y
    const Vec<W> o0 = -(s01 + e2), o1 = d01 - e2, o2 = -(d01 + e2), o3 = s01 - e2;
    store<W>(offset[0] + W * c, o0);  // -x-y-z
    store<W>(offset[1] + W * c, o1);  // +x-y-z
    store<W>(offset[2] + W * c, o2);  // -x+y-z
    store<W>(offset[3] + W * c, o3);  // +x+y-z
    store<W>(offset[7] + W * c, -o0);
    store<W>(offset[6] + W * c, -o1);
    store<W>(offset[5] + W * c, -o2);
    store<W>(offset[4] + W * c, -o3);
  }
}

// A group: three lanes of a lane table under construction, and a fourth
// (zero when made, and not stored). A 4-lane vector, or in the portable build
// (2-lane registers) two halves, where 4-lane vectors are built through the
// stack. The same operations lane by lane either way: the same bits.
struct HalfPair {
  Vec<2> lo, hi;  // lanes 0, 1 and 2, 3
};
[[gnu::always_inline]] inline HalfPair operator+(const HalfPair& a, const HalfPair& b) {
  return {a.lo + b.lo, a.hi + b.hi};
}
[[gnu::always_inline]] inline HalfPair operator*(const HalfPair& a, const HalfPair& b) {
  return {a.lo * b.lo, a.hi * b.hi};
}
[[gnu::always_inline]] inline HalfPair operator*(const HalfPair& a, double s) { return {a.lo * s, a.hi * s}; }
[[gnu::always_inline]] inline HalfPair operator-(const HalfPair& a) { return {-a.lo, -a.hi}; }
template <int W>
using Group = std::conditional_t<W == 2, HalfPair, v4d>;

// {a, b, c, 0} built in registers (as v4d{a, b, c, 0}, GCC wrote the four
// to the stack and read them back as one vector, which waits for the stores).
[[gnu::always_inline]] inline void make_group(v4d& out, double a, double b, double c) {
  const Vec<2> lo = {a, b}, hi = {c, 0};
  out = __builtin_shufflevector(lo, hi, 0, 1, 2, 3);
}
[[gnu::always_inline]] inline void make_group(HalfPair& out, double a, double b, double c) {
  out = {Vec<2>{a, b}, Vec<2>{c, 0}};
}
// The lanes {2, 2, 1} and {1, 0, 0} of g (the cross axes' other two terms).
[[gnu::always_inline]] inline void cross_lanes(const v4d& g, v4d& x, v4d& y) {
  x = __builtin_shufflevector(g, g, 2, 2, 1, 3), y = __builtin_shufflevector(g, g, 1, 0, 0, 3);
}
[[gnu::always_inline]] inline void cross_lanes(const HalfPair& g, HalfPair& x, HalfPair& y) {
  x = {__builtin_shufflevector(g.hi, g.hi, 0, 0), __builtin_shufflevector(g.lo, g.hi, 1, 3)};
  y = {__builtin_shufflevector(g.lo, g.lo, 1, 0), __builtin_shufflevector(g.lo, g.hi, 0, 3)};
}

// 16 lanes from five groups (lanes 0..2 of g0..g4), lane 15 zero: aligned
// stores of the build's width (one load of a lane chunk then finds one store).
[[gnu::always_inline]] inline void store_groups(double* out, const v4d& g0, const v4d& g1, const v4d& g2,
                                                const v4d& g3, const v4d& g4) {
  store<4>(out, __builtin_shufflevector(g0, g1, 0, 1, 2, 4));
  store<4>(out + 4, __builtin_shufflevector(g1, g2, 1, 2, 4, 5));
  store<4>(out + 8, __builtin_shufflevector(g2, g3, 2, 4, 5, 6));
  store<4>(out + 12, __builtin_shufflevector(g4, v4d{}, 0, 1, 2, 4));
}
[[gnu::always_inline]] inline void store_groups(double* out, const HalfPair& g0, const HalfPair& g1,
                                                const HalfPair& g2, const HalfPair& g3, const HalfPair& g4) {
  store<2>(out, g0.lo);
  store<2>(out + 2, __builtin_shufflevector(g0.hi, g1.lo, 0, 2));
  store<2>(out + 4, __builtin_shufflevector(g1.lo, g1.hi, 1, 2));
  store<2>(out + 6, g2.lo);
  store<2>(out + 8, __builtin_shufflevector(g2.hi, g3.lo, 0, 2));
  store<2>(out + 10, __builtin_shufflevector(g3.lo, g3.hi, 1, 2));
  store<2>(out + 12, g4.lo);
  store<2>(out + 14, __builtin_shufflevector(g4.hi, Vec<2>{}, 0, 2));
}

// out = a + b, the first kTested lanes: a child's projections in collide_all,
// its parent's plus its offset already scaled to its depth, as the kernel
// computes them.
template <int W, int kTested>
[[gnu::always_inline]] inline void add_lanes(double* out, const double* a, const double* b) {
  for (int k = 0; k < kTested; k += W) {
    Vec<W> x, y;
    load<W>(x, a + k);
    load<W>(y, b + k);
    store<W>(out + k, x + y);
  }
}

std::atomic<BoxKernel> chosen_kernel{BoxKernel::best};
std::atomic<bool> shared_axis_shortcut{true};

bool cpu_has(BoxKernel k) {
  switch (k) {
    case BoxKernel::best:
    case BoxKernel::portable:
      return true;
#ifdef OCTBAKE_X86_KERNELS
    case BoxKernel::avx2:
      return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    case BoxKernel::avx512:
      return __builtin_cpu_supports("avx512f");
#else
    default:
      return false;
#endif
  }
  return false;
}

constexpr int kPathLevels = 2 * kMaxDepth;

// One step of the descent. Which box splits depends only on the two depths
// (da, db), and every step adds one to da + db, so all box pairs at path
// level L = da + db have the same depths and split the same side. A level is
// worked out when the descent first expands a pair there (levels are reached
// in order; most pair tests end after a few): its split and its tables.
// collide_all (kScaled) scales the offsets once per level, and collide,
// which mostly expands few pairs per level, in the kernel.
struct Level {
  alignas(64) Lanes radius;  // radii of a child and of the other box, summed
  const Lanes* offset;       // the children's offsets, octant order (times scale)
  double scale;              // 1 if kScaled, else 2^-d
  const uint8_t* masks;      // child masks of the split tree at depth d
  const uint32_t* first_child;  // and the index of each box's first child at d + 1
  uint8_t da, db;            // depths of the box pairs at this level
  bool split_a;              // A's box splits (else B's)
  bool other_leaf;           // the other box is a leaf (containment early out)
  uint8_t d;                 // depth of the split box (its children: d + 1)
  uint8_t other;             // depth of the other box
};

// ---- The pair frame --------------------------------------------------------
// Per pair: the projection matrix W (p = W t), the radii's terms, and lazily:
// per tree the depth-1 child offsets, per level its split, summed radii and
// (scaled) offsets.
template <class K>
class PairFrame {
  static constexpr int W = K::kStoreLanes;  // the build's vector width
  using V = Vec<W>;

 public:
  [[gnu::always_inline]] PairFrame(const PlacedTree& a, const PlacedTree& b)
      : rel_(a, b) {
    const Eigen::Matrix3d& r = rel_.r;
    const Eigen::Matrix3d& abs_r = rel_.abs_r;
    // Lanes as in the kernel, built from the rows of R and |R| and the
    // columns of |R| (|R| padded; lane 3 zero) in groups of three lanes.
    using G = Group<W>;
    G rr[3], ar[3], ac[3];
    for (int m = 0; m < 3; ++m) {
      make_group(rr[m], r(m, 0), r(m, 1), r(m, 2));
      make_group(ar[m], abs_r(m, 0), abs_r(m, 1), abs_r(m, 2));
      make_group(ac[m], abs_r(0, m), abs_r(1, m), abs_r(2, m));
    }
    // t_.w[m]: weight of t_m in each projection: e_m on A's faces, row m of R
    // on B's, and on A_i x B_j (t_i2 r_i1j - t_i1 r_i2j) row i1 where m = i2,
    // minus row i2 where m = i1.
    G zero, e[3];
    make_group(zero, 0, 0, 0);
    make_group(e[0], 1, 0, 0);
    make_group(e[1], 0, 1, 0);
    make_group(e[2], 0, 0, 1);
    store_groups(t_.w[0], e[0], rr[0], zero, rr[2], -rr[1]);
    store_groups(t_.w[1], e[1], rr[1], -rr[2], zero, rr[0]);
    store_groups(t_.w[2], e[2], rr[2], rr[1], -rr[0], zero);
    const Aabb& ba = a.tree->bounds();
    const Aabb& bb = b.tree->bounds();
    a_min_ = ba.min;
    b_min_ = bb.min;
    a_size_ = ba.max - ba.min;
    b_size_ = bb.max - bb.min;
    // The radii (Gottschalk's formulas) of A's root, half extents h in A's
    // axes: h on A's faces, |R|^T h on B's, h_i1 |R|_i2j + h_i2 |R|_i1j on
    // A_i x B_j; B's root (g, in B's axes): |R| g on A's faces, g on B's,
    // g_j1 |R|_ij2 + g_j2 |R|_ij1 on A_i x B_j. Padding: the same sums of
    // |R| times pad. Terms summed in the order of h_0, h_1, h_2 (g_0, g_1,
    // g_2): the bits do not depend on how the lanes are built.
    const double h0 = 0.5 * a_size_[0], h1 = 0.5 * a_size_[1], h2 = 0.5 * a_size_[2];
    const double g0 = 0.5 * rel_.s * b_size_[0], g1 = 0.5 * rel_.s * b_size_[1], g2 = 0.5 * rel_.s * b_size_[2];
    const double pad = rel_.pad;
    G pads, half_a, half_b;
    make_group(pads, pad, pad, pad);
    make_group(half_a, h0, h1, h2);
    make_group(half_b, g0, g1, g2);
    store_groups(t_.base_a, half_a, (ar[0] * h0 + ar[1] * h1) + ar[2] * h2, ar[2] * h1 + ar[1] * h2,
                 ar[2] * h0 + ar[0] * h2, ar[1] * h0 + ar[0] * h1);
    store_groups(t_.padding_a, pads, ((ar[0] + ar[1]) + ar[2]) * pad, (ar[2] + ar[1]) * pad, (ar[2] + ar[0]) * pad,
                 (ar[1] + ar[0]) * pad);
    G gj1, gj2;  // g_j1 / g_j2 by lane j, each in the order of g
    make_group(gj1, g1, g0, g0);
    make_group(gj2, g2, g2, g1);
    G cross_b[3], cross_pad_b[3];
    for (int i = 0; i < 3; ++i) {
      G x, y;
      cross_lanes(ar[i], x, y);
      cross_b[i] = gj1 * x + gj2 * y;
      cross_pad_b[i] = (x + y) * pad;
    }
    store_groups(t_.base_b, (ac[0] * g0 + ac[1] * g1) + ac[2] * g2, half_b, cross_b[0], cross_b[1],
                 cross_b[2]);
    store_groups(t_.padding_b, ((ac[0] + ac[1]) + ac[2]) * pad, pads, cross_pad_b[0], cross_pad_b[1],
                 cross_pad_b[2]);
    // For the split schedule (fill_level): half diagonals in A's units.
    size_a_ = (0.5 * a_size_).squaredNorm();
    size_b_ = (0.5 * rel_.s * b_size_).squaredNorm();
    tree_a_ = a.tree;
    tree_b_ = b.tree;
    depth_a_ = a.depth;
    depth_b_ = b.depth;
    shares_axis_ = octbake::shares_axis(r);
    scale_a_ = a.pose.scale;
  }

  int levels() const { return depth_a_ + depth_b_; }
  bool shares_axis() const { return shares_axis_; }

  // The lanes the set-up fills for a descent that tests kTested lanes
  // (lanes 0..kSetUp - 1; see Portable::kNarrowSetUp).
  template <int kTested>
  static constexpr int kSetUp = K::kNarrowSetUp ? kTested : kLanes;

  // Level l, worked out on first use: the descent expands a pair at level l
  // only after one at l - 1 (one descent uses the frame, so always the same
  // kScaled and kTested).
  template <bool kScaled, int kTested>
  [[gnu::always_inline]] const Level& level(int l) const {
    assert(l <= known_levels_);
    if (l == known_levels_) fill_level<kScaled, kTested>(l);
    return level_[l];
  }
  // A level already worked out.
  const Level& known_level(int l) const { return level_[l]; }

  // Projections of box pair (A's ca at da, B's cb at db).
  template <int kTested>
  void project(const Coord& ca, int da, const Coord& cb, int db, Lanes& p) const {
    const Eigen::Vector3d qa = a_min_ + kHalfPow[da] * a_size_.cwiseProduct(cell_center(ca));
    const Eigen::Vector3d qb = b_min_ + kHalfPow[db] * b_size_.cwiseProduct(cell_center(cb));
    const Eigen::Vector3d t = (rel_.t + rel_.sr * qb) - qa;
    const Lanes* w = t_.w;
    for (int k = 0; k < kSetUp<kTested>; k += W) {
      V w0, w1, w2;
      load<W>(w0, w[0] + k);
      load<W>(w1, w[1] + k);
      load<W>(w2, w[2] + k);
      store<W>(p + k, (w0 * t[0] + w1 * t[1]) + w2 * t[2]);
    }
  }

  template <int kTested>
  bool overlap(const double* p, int da, int db) const {
    typename Chunk<W>::mask separated{};
    for (int k = 0; k < kSetUp<kTested>; k += W) {
      V pk, r;
      load<W>(pk, p + k);
      radius(r, k, kHalfPow[da], kHalfPow[db]);
      mark_exceeding<W>(separated, pk, r);
    }
    return !any_lane<W>(separated);
  }

  // The summed radii of box pairs at depths (da, db), lanes 0..kTested - 1.
  template <int kTested>
  void radii(int da, int db, Lanes& r) const {
    for (int k = 0; k < kSetUp<kTested>; k += W) {
      V x;
      radius(x, k, kHalfPow[da], kHalfPow[db]);
      store<W>(r + k, x);
    }
  }

  // How far B may be translated relative to A (A's units) with the box pair
  // of projections q and summed radii r still separated on one of lanes
  // 0..kTested - 1, as this test computes it (<= 0: not separated by a
  // margin). Lane k's projection is w_k . t (w_k: column k of t_.w), so a
  // translation dt moves it by at most |w_k| |dt|; the radii's padding
  // follows |t| (Relative::pad), and grows by at most 4 kRelPad |dt|. The
  // slack, 2 pad (1 + |w_k|_1), covers the rounding of q along another path
  // of sums (~1e-15 of the same magnitudes; pad is 1e-9 of them).
  template <int kTested>
  double separation(const double* q, const double* r) const {
    static constexpr Lanes kZero{};
    return least_separation<kTested>(q, &kZero, 1, 1, r, std::numeric_limits<double>::infinity());
  }
  // min(least, the separations of the child box pairs in `children` (bit j:
  // projections parent + offset[j] * scale)), the same bits as separation()
  // of each. A child with a lane of at least the least so far cannot lower
  // it and stops at that lane's chunk: most children then cost a chunk or
  // two, not all of them and a reduction (a 6-6 miss's full separation: 1.3-1.4x
  // its plain test, was 1.6-2.0x; bench_pair BM_Separation).
  template <int kTested>
  double least_separation(const double* parent, const Lanes* offset, uint32_t children, double scale,
                          const double* r, double least) const {
    if (!separation_lanes_) {
      for (int k = 0; k < kLanes; ++k) {
        const double w0 = t_.w[0][k], w1 = t_.w[1][k], w2 = t_.w[2][k];
        sep_.slack[k] = 2 * rel_.pad * (1 + (std::abs(w0) + std::abs(w1) + std::abs(w2)));
        const double norm = std::sqrt((w0 * w0 + w1 * w1) + w2 * w2);
        sep_.per_unit[k] = norm > 0 ? 1 / (norm + 4 * kRelPad) : 0;  // lane 15 (and zero edge axes): never
      }
      separation_lanes_ = true;
    }
    using M = typename Chunk<W>::mask;
    for (; children != 0; children &= children - 1) {
      const double* o = offset[std::countr_zero(children)];
      const V bound = V{} + least;
      V best{};
      bool lowers = true;
      for (int k = 0; k < kTested; k += W) {
        V x, ok, radius, slack, per_unit;
        load<W>(x, parent + k);
        load<W>(ok, o + k);
        load<W>(radius, r + k);
        load<W>(slack, sep_.slack + k);
        load<W>(per_unit, sep_.per_unit + k);
        x = x + ok * scale;  // as K::add_scaled (scale is a power of two: the product is exact)
        const V gap = ((V(M(x) & INT64_MAX) - radius) - slack) * per_unit;
        if (K::any_at_least(gap, bound)) {  // this child's separation is at least `least`
          lowers = false;
          break;
        }
        best = gap > best ? gap : best;
      }
      if (!lowers) continue;
      double out = 0;
      for (int i = 0; i < W; ++i) out = std::max(out, best[i]);
      least = std::min(least, out);
    }
    return least;
  }
  // A's scale: A's units to world units.
  double scale_a() const { return scale_a_; }

  // Does the padded box of one side lie inside the other's, with a margin of
  // one pad for rounding? Then every leaf under the inner box overlaps the
  // outer box. Checked on the outer box's face axes (lanes 0..2 for A, 3..5
  // for B), where the inner box's radius bounds its extent (|R| padded).
  // Here: does the box about to split at level l lie inside the other one?
  bool split_box_inside(const double* p, const Level& lv) const {
    const double hi = kHalfPow[lv.d], ho = kHalfPow[lv.other];
    return lv.split_a ? inside(p, t_.base_a, t_.padding_a, hi, t_.base_b, t_.padding_b, ho, 3)
                      : inside(p, t_.base_b, t_.padding_b, hi, t_.base_a, t_.padding_a, ho, 0);
  }

  // Test the children of the split box of level l against the other box: see
  // children_overlap.
  template <bool kScaled, int kTested>
  [[gnu::always_inline]] static uint32_t children_overlap(const Level& t, const double* parent,
                                                          const uint8_t* octant, int n) {
    return K::template children_overlap<!kScaled, kTested>(parent, t.radius, t.offset, t.scale, octant, n);
  }

  // w_k = p . u_k (see NearestTables) for the tree split at lv, summed in
  // the order of m, with p's lanes below kOrderFloor as 0: the same bits in
  // every build.
  void nearest_weights(const double* p, const Level& lv, double (&w)[3]) const {
    const double(&u)[3][3] = lv.split_a ? steps_a_ : steps_b_;
    double c[3];
    for (int m = 0; m < 3; ++m) c[m] = std::abs(p[m]) < kOrderFloor ? 0.0 : p[m];
    for (int k = 0; k < 3; ++k) w[k] = (c[0] * u[k][0] + c[1] * u[k][1]) + c[2] * u[k][2];
  }

 private:
  template <bool kScaled, int kTested>
  void fill_level(int l) const {
    Level& lv = level_[l];
    int da = 0, db = 0;
    if (l > 0) {
      const Level& up = level_[l - 1];
      da = up.da + up.split_a;
      db = up.db + !up.split_a;
    }
    // The larger box splits (half diagonals, both halving with each depth; a
    // tree already at its depth cannot).
    const bool sa = da < depth_a_ && (db == depth_b_ || size_a_ * kHalfPow[2 * da] >= size_b_ * kHalfPow[2 * db]);
    lv.da = uint8_t(da);
    lv.db = uint8_t(db);
    lv.split_a = sa;
    lv.d = uint8_t(sa ? da : db);
    lv.other = uint8_t(sa ? db : da);
    lv.other_leaf = sa ? db == depth_b_ : da == depth_a_;
    const ObjectTree& split_tree = sa ? *tree_a_ : *tree_b_;
    lv.masks = split_tree.masks().masks[size_t(lv.d)].data();
    lv.first_child = split_tree.first_children(lv.d);
    // Radii of the box pairs below: the split side one depth deeper.
    const double ha = kHalfPow[da + sa], hb = kHalfPow[db + !sa];
    for (int k = 0; k < kSetUp<kTested>; k += W) {
      V r;
      radius(r, k, ha, hb);
      store<W>(lv.radius + k, r);
    }
    const Lanes* depth1 = sa ? offsets_a<kTested>() : offsets_b<kTested>();
    lv.offset = depth1;
    lv.scale = kHalfPow[lv.d];
    if (kScaled) {
      lv.scale = 1;
      if (lv.d > 0) {
        // Scaled by a power of two: exact, the same bits as scaling in the kernel.
        const double h = kHalfPow[lv.d];
        Lanes* scaled = level_offsets_[l];
        for (int j = 0; j < 8; ++j)
          for (int k = 0; k < kSetUp<kTested>; k += W) {
            V x;
            load<W>(x, depth1[j] + k);
            store<W>(scaled[j] + k, x * h);
          }
        lv.offset = scaled;
      }
    }
    ++known_levels_;
  }

  // The projection matrix in chunks: w[m][c] = lanes W c..W c + W - 1 of t_.w[m].
  void load_weights(V (&w)[3][kLanes / W]) const {
    for (int m = 0; m < 3; ++m)
      for (int c = 0; c < kLanes / W; ++c) load<W>(w[m][c], t_.w[m] + W * c);
  }

  // The depth-1 child offsets of A's (B's) root, filled on first use.
  template <int kTested>
  const Lanes* offsets_a() const {
    if (!(filled_offsets_ & 1u)) {
      V w[3][kLanes / W];
      load_weights(w);
      const double quarter[3] = {0.25 * a_size_[0], 0.25 * a_size_[1], 0.25 * a_size_[2]};
      // t = centre B - centre A: A's child moving by +q moves t by -q.
      fill_offsets<W, kSetUp<kTested>>(t_.offset_a, w, quarter, -1.0);
      // Its depth-1 steps u_k (nearest_weights).
      for (int k = 0; k < 3; ++k)
        for (int m = 0; m < 3; ++m) steps_a_[k][m] = m == k ? -quarter[k] : 0.0;
      filled_offsets_ |= 1u;
    }
    return t_.offset_a;
  }
  template <int kTested>
  const Lanes* offsets_b() const {
    if (!(filled_offsets_ & 2u)) {
      V w[3][kLanes / W];
      load_weights(w);
      // B's local axis j moves its centre by sR e_j in A's frame.
      const Eigen::Matrix3d& sr = rel_.sr;
      V wb[3][kLanes / W];
      for (int c = 0; c < kSetUp<kTested> / W; ++c)
        for (int j = 0; j < 3; ++j) wb[j][c] = (w[0][c] * sr(0, j) + w[1][c] * sr(1, j)) + w[2][c] * sr(2, j);
      const double quarter[3] = {0.25 * b_size_[0], 0.25 * b_size_[1], 0.25 * b_size_[2]};
      fill_offsets<W, kSetUp<kTested>>(t_.offset_b, wb, quarter, 1.0);
      for (int k = 0; k < 3; ++k)
        for (int m = 0; m < 3; ++m) steps_b_[k][m] = quarter[k] * sr(m, k);
      filled_offsets_ |= 2u;
    }
    return t_.offset_b;
  }

  // Lanes k..k+W-1 of the summed radii of A's box at scale ha = 2^-da and B's
  // at hb: each radius is base * 2^-d + padding (computed where needed: a
  // table per depth cost more than it saved).
  [[gnu::always_inline]] void radius(V& r, int k, double ha, double hb) const {
    V ba, pa, bb, pb;
    load<W>(ba, t_.base_a + k);
    load<W>(pa, t_.padding_a + k);
    load<W>(bb, t_.base_b + k);
    load<W>(pb, t_.padding_b + k);
    r = (ba * ha + pa) + (bb * hb + pb);
  }

  bool inside(const double* p, const double* inner_base, const double* inner_padding, double hi,
              const double* outer_base, const double* outer_padding, double ho, int lane) const {
    bool in = true;
    for (int k = lane; k < lane + 3; ++k)
      in &= (std::abs(p[k]) + (inner_base[k] * hi + inner_padding[k])) + rel_.pad <=
            outer_base[k] * ho + outer_padding[k];
    return in;
  }

  Relative rel_;
  Eigen::Vector3d a_min_, b_min_, a_size_, b_size_;  // root sizes
  double size_a_, size_b_;  // squared half diagonals in A's units
  const ObjectTree *tree_a_, *tree_b_;
  int depth_a_, depth_b_;
  bool shares_axis_;
  double scale_a_;
  // Filled lazily (the frame is used by one descent only).
  mutable LaneTables t_;
  // The depth-1 steps u_k, [k][m], filled with their offsets.
  mutable double steps_a_[3][3], steps_b_[3][3];
  mutable Level level_[kPathLevels];
  alignas(64) mutable Lanes level_offsets_[kPathLevels][8];
  mutable int known_levels_ = 0;  // levels 0..known_levels_ - 1 are worked out
  mutable uint32_t filled_offsets_ = 0;
  // separation()'s per-lane slack and 1 / (|w_k| + 4 kRelPad), on first use.
  mutable struct {
    Lanes slack, per_unit;
  } sep_;
  mutable bool separation_lanes_ = false;
};

// Box coordinates packed in one word, 21 bits per axis: a child is its parent
// shifted left by one, or'ed with its octant's bits.
using Packed = uint64_t;
constexpr Packed kOctantBits[8] = {0, 1, 1ull << 21, 1 + (1ull << 21), 1ull << 42, 1 + (1ull << 42),
                                   (1ull << 21) + (1ull << 42), 1 + (1ull << 21) + (1ull << 42)};
[[gnu::always_inline]] inline Packed child_of(Packed c, uint8_t octant) { return (c << 1) | kOctantBits[octant]; }
[[gnu::always_inline]] inline Coord unpack(Packed c) {
  constexpr Packed m = (1u << 21) - 1;
  return {uint16_t(c & m), uint16_t((c >> 21) & m), uint16_t((c >> 42) & m)};
}

// Some occupied leaf (at `depth`) under box (d, index, c), lowest octants
// first; false if the box has none.
bool some_leaf(const ObjectTree& tree, int depth, int d, uint32_t index, const Coord& c, Coord& leaf) {
  if (d == depth) return leaf = c, true;
  const uint8_t mask = tree.mask(d, index);
  const uint32_t first = tree.first_child(d, index);
  for (int k = 0; k < kOctants.count[mask]; ++k) {
    const uint8_t j = kOctants.octant[mask][k];
    const Coord child{uint16_t(2 * c[0] + (j & 1u)), uint16_t(2 * c[1] + ((j >> 1) & 1u)),
                      uint16_t(2 * c[2] + ((j >> 2) & 1u))};
    if (some_leaf(tree, depth, d + 1, first + uint32_t(k), child, leaf)) return true;
  }
  return false;
}

// collide's depth-first descent in canonical order, nearest children first,
// calling on_leaf(a's leaf, b's leaf) for the first overlapping leaf pair.
//
// Depth first, the box pairs waiting at path level L + 1 are all children of
// the one pair open at level L, so the descent keeps one record per level: the
// open pair (projections, indices, coordinates) and its overlapping children
// still to visit, in visiting order. A child's projections are recomputed
// from its parent's when it is visited (the same sums the kernel did).
//
// With kSeparation, after a miss `separation` is the least, over the box
// pairs found separated (the roots, or children not visited), of how far B
// may move with that pair still separated (PairFrame::separation; A's units):
// every leaf pair lies under one of them, so moving B less than that leaves
// the descent's answer a miss. Once it is below `floor` (A's units) it is
// not worked out further (0 is returned).
template <class K, int kTested, bool kSeparation, class OnLeaf>
[[gnu::always_inline]] inline void descend(const PairFrame<K>& frame, const PlacedTree& a, const PlacedTree& b,
                                           PairTest& result, double& separation, double floor,
                                           OnLeaf on_leaf) {
  struct Open {
    alignas(64) Lanes p;
    Packed coord[2];     // A's, B's
    uint32_t index[2];   // level indices, A's, B's
    uint32_t first;      // first child of the split box
    uint32_t order;      // the 8 octants in visiting order, 3 bits each
    uint32_t left;       // bit i: order's i-th is still to visit
    uint8_t mask;        // the split box's child mask
  };
  Open open[kPathLevels + 1];
  frame.template project<kTested>({0, 0, 0}, 0, {0, 0, 0}, 0, open[0].p);
  ++result.box_tests;
  if (!frame.template overlap<kTested>(open[0].p, 0, 0)) {
    if constexpr (kSeparation) {
      Lanes r;
      frame.template radii<kTested>(0, 0, r);
      separation = frame.template separation<kTested>(open[0].p, r);
    }
    return;
  }
  if constexpr (kSeparation) separation = std::numeric_limits<double>::infinity();
  const int levels = frame.levels();
  if (levels == 0) {  // neither can split: the roots are the leaf pair
    result.hit = true;
    on_leaf(Coord{0, 0, 0}, Coord{0, 0, 0});
    return;
  }
  open[0].coord[0] = open[0].coord[1] = 0;
  open[0].index[0] = open[0].index[1] = 0;
  // Counted in a local (a register): result may alias what on_leaf writes.
  uint64_t box_tests = result.box_tests;
  Open* top = open;  // the pair open at the deepest level, l
  int l = 0;
  for (;;) {
    // Expand the pair open at level l.
    Open& o = *top;
    const Level& lv = frame.template level<false, kTested>(l);
    const int side = lv.split_a ? 0 : 1;
    const uint32_t index = o.index[side];
    // The other box is a leaf and holds this one whole: any leaf below is a
    // proof (counted as the one box test it replaces).
    if (lv.other_leaf && frame.split_box_inside(o.p, lv)) {
      Coord leaf;
      const ObjectTree& tree = lv.split_a ? *a.tree : *b.tree;
      if (some_leaf(tree, lv.split_a ? a.depth : b.depth, lv.d, index, unpack(o.coord[side]), leaf)) {
        result.box_tests = box_tests + 1;
        result.hit = true;
        const Coord other = unpack(o.coord[1 - side]);
        lv.split_a ? on_leaf(leaf, other) : on_leaf(other, leaf);
        return;
      }
    }
    const uint8_t mask = lv.masks[index];
    const int count = kOctants.count[mask];
    const uint32_t hits =
        PairFrame<K>::template children_overlap<false, kTested>(lv, o.p, kOctants.octant[mask], count);
    box_tests += uint64_t(count);
    if constexpr (kSeparation)
      if (separation >= floor)
        separation =
            frame.template least_separation<kTested>(o.p, lv.offset, mask & ~hits, lv.scale, lv.radius, separation);
    o.left = 0;
    if (hits != 0) {
      if ((hits & (hits - 1)) == 0) {  // one child
        o.order = uint32_t(std::countr_zero(hits));
        o.left = 1;
      } else {
        double w[3];
        frame.nearest_weights(o.p, lv, w);
        nearest_first(w, hits, o.order, o.left);
      }
      if (l + 1 == levels) {
        // The children are leaf pairs: the nearest is reported here.
        result.hit = true;
        const Packed grown = child_of(o.coord[side], uint8_t((o.order >> (3 * std::countr_zero(o.left))) & 7u));
        lv.split_a ? on_leaf(unpack(grown), unpack(o.coord[1])) : on_leaf(unpack(o.coord[0]), unpack(grown));
        result.box_tests = box_tests;
        return;
      }
      o.first = lv.first_child[index];
      o.mask = mask;
    }
    // Back to the deepest level with a child left to visit.
    for (; top->left == 0; --l)
      if (top-- == open) {
        result.box_tests = box_tests;
        return;
      }
    Open& parent = *top;
    const Level& plv = frame.known_level(l);
    Open& child = *++top;
    ++l;
    const uint8_t j = uint8_t((parent.order >> (3 * std::countr_zero(parent.left))) & 7u);
    parent.left &= parent.left - 1;
    const int split = plv.split_a ? 0 : 1;
    K::template add_scaled<kTested>(child.p, parent.p, plv.offset[j], plv.scale);
    child.index[0] = parent.index[0], child.index[1] = parent.index[1];
    child.coord[0] = parent.coord[0], child.coord[1] = parent.coord[1];
    child.index[split] = parent.first + K::bits_below(parent.mask, j);
    child.coord[split] = child_of(parent.coord[split], j);
  }
}

// Every overlapping leaf pair (collide_all), breadth first in batches.
// Every overlapping pair is visited, so the order of the visits does not
// change which boxes are tested: the pairs of a level are expanded a batch at
// a time, their occupied children listed (octant table) and tested in one
// flat loop whose results are kept as bits (on half of the lanes: see
// below), then the overlapping ones taken
// in order (the depth-first walk branched on "any child? how many? back up?"
// at every pair, and mispredicted most of them; writing the overlapping ones'
// indices at a position that depends on each result stalled the loads that
// follow, so the results are bits first). A level's list is
// consumed before the next batch of the level above, so memory stays bounded
// (8 kBatch pairs a level) and the leaf pairs come out in depth-first order,
// children in octant order. The leaf level is reported, not stored.
constexpr int kBatch = 32;
constexpr int kLevelCap = 8 * kBatch;
// The box pairs of one level (projections apart: a pair's is at p + 16 i).
struct SweepLevel {
  alignas(64) Lanes p[kLevelCap];
  Packed coord[kLevelCap][2];    // A's, B's
  uint32_t index[kLevelCap][2];  // level indices, A's, B's
};

template <class K, int kTested, class OnLeaf>
[[gnu::always_inline]] inline void sweep_all(const PairFrame<K>& frame, PairTest& result, OnLeaf on_leaf) {
  Lanes root;
  frame.template project<kTested>({0, 0, 0}, 0, {0, 0, 0}, 0, root);
  ++result.box_tests;
  if (!frame.template overlap<kTested>(root, 0, 0)) return;
  const int levels = frame.levels();
  if (levels == 0) {  // neither can split: the roots are the leaf pair
    result.hit = true;
    on_leaf(Coord{0, 0, 0}, Coord{0, 0, 0});
    return;
  }
  // Per thread, reused: one list per level but the leaves'.
  static thread_local std::vector<SweepLevel> lists;
  if (lists.size() < size_t(levels)) lists.resize(size_t(levels));
  SweepLevel* const list = lists.data();
  std::memcpy(list[0].p[0], root, sizeof(double) * PairFrame<K>::template kSetUp<kTested>);
  list[0].coord[0][0] = list[0].coord[0][1] = 0;
  list[0].index[0][0] = list[0].index[0][1] = 0;
  int size[kPathLevels], head[kPathLevels];
  size[0] = 1, head[0] = 0;
  uint64_t box_tests = result.box_tests;
  int l = 0;
  for (;;) {
    // The deepest level with pairs left to expand.
    for (; head[l] == size[l]; --l)
      if (l == 0) {
        result.box_tests = box_tests;
        return;
      }
    const Level& lv = frame.template level<true, kTested>(l);
    const int side = lv.split_a ? 0 : 1;
    const SweepLevel& in = list[l];
    const int begin = head[l], end = std::min(size[l], begin + kBatch);
    head[l] = end;
    // The occupied children of the batch, in order (8 written, count kept).
    // Candidate c of pair i is child c - (pair i's first candidate) of its
    // box: its level index is child_base[i] + c.
    uint8_t octant[kLevelCap + 8];
    uint8_t parent[kLevelCap + 8];
    uint32_t child_base[kBatch];
    int n = 0;
    for (int i = 0; i < end - begin; ++i) {
      const uint32_t index = in.index[begin + i][side];
      const uint8_t mask = lv.masks[index];
      std::memcpy(octant + n, kOctants.octant[mask], 8);
      std::memset(parent + n, i, 8);
      child_base[i] = lv.first_child[index] - uint32_t(n);
      n += kOctants.count[mask];
    }
    box_tests += uint64_t(n);
    const Lanes* batch = in.p + begin;
    // Test them on lanes 0..7 (the six face axes and two edge axes): bit c
    // of near[c / 64] tells whether candidate c passes. Most separated
    // children fail there (on the spider-duck 6-6 pairs 62-66% of all
    // candidates fail, 0-2% more on lanes 8..15), so lanes 8..15 are tested
    // only for those that pass, as they are taken in order below. A branch, not bits: it
    // almost always goes the same way, and as bits it was slower (the pass
    // had to be walked twice or the writes below made to depend on it).
    uint64_t near[kLevelCap / 64];
    const int words = (n + 63) / 64;
    for (int w = 0; w < words; ++w) {
      uint64_t bits = 0;
      for (int c = 64 * w, last = std::min(n, c + 64); c < last; ++c)
        bits |= uint64_t(K::template half_overlaps<0>(batch[parent[c]], lv.offset[octant[c]], lv.radius)) << (c & 63);
      near[w] = bits;
    }
    // The overlapping ones, in order: leaf pairs reported, others listed.
    const bool leaves = l + 1 == levels;
    SweepLevel& out = list[leaves ? l : l + 1];
    int m = 0;
    for (int w = 0; w < words; ++w)
      for (uint64_t bits = near[w]; bits != 0; bits &= bits - 1) {
        const int c = 64 * w + std::countr_zero(bits);
        if (kTested == kLanes && !K::template half_overlaps<1>(batch[parent[c]], lv.offset[octant[c]], lv.radius))
          continue;
        const int i = begin + parent[c];
        const uint8_t j = octant[c];
        const Packed grown = child_of(in.coord[i][side], j);
        if (leaves) {
          side == 0 ? on_leaf(unpack(grown), unpack(in.coord[i][1])) : on_leaf(unpack(in.coord[i][0]), unpack(grown));
          ++m;
          continue;
        }
        add_lanes<K::kStoreLanes, kTested>(out.p[m], in.p[i], lv.offset[j]);
        out.coord[m][0] = in.coord[i][0], out.coord[m][1] = in.coord[i][1];
        out.index[m][0] = in.index[i][0], out.index[m][1] = in.index[i][1];
        out.coord[m][side] = grown;
        out.index[m][side] = child_base[parent[c]] + uint32_t(c);
        ++m;
      }
    if (leaves) {
      result.hit |= m > 0;
      continue;
    }
    size[l + 1] = m, head[l + 1] = 0;
    ++l;
  }
}

// The pair in canonical order, the leaf pair mapped back on the way out.
struct Canonical {
  const PlacedTree& first;
  const PlacedTree& second;
  bool swapped;
  Canonical(const PlacedTree& a, const PlacedTree& b) : Canonical(a, b, !goes_first(a, b)) {}
  Canonical(const PlacedTree& a, const PlacedTree& b, bool swap)
      : first(swap ? b : a), second(swap ? a : b), swapped(swap) {}
  LeafPair to_caller(const Coord& c1, const Coord& c2) const {
    return swapped ? LeafPair{to_coord(c2), to_coord(c1)} : LeafPair{to_coord(c1), to_coord(c2)};
  }
};

// One pair test: collide() with an optional leaf pair (in the caller's order)
// to try first, collide_all() if `all` is given, or collide() with its
// separation if `separation` is.
struct Job {
  const Canonical& pair;
  const LeafPair* hint;
  std::vector<LeafPair>* all;
  double* separation;
};
enum class Kind { first_hit, all, separation };

template <class K, Kind kKind, int kTested>
[[gnu::always_inline]] inline PairTest test_pair(const Job& job, const PairFrame<K>& frame) {
  const Canonical& pair = job.pair;
  PairTest result;
  if constexpr (kKind == Kind::all) {
    sweep_all<K, kTested>(frame, result,
                          [&](const Coord& ca, const Coord& cb) { job.all->push_back(pair.to_caller(ca, cb)); });
    return result;
  }
  if (job.hint) {
    const LeafPair& hint = *job.hint;
    const Coord c1 = from_coord(pair.swapped ? hint.b : hint.a), c2 = from_coord(pair.swapped ? hint.a : hint.b);
    Lanes p;
    frame.template project<kTested>(c1, pair.first.depth, c2, pair.second.depth, p);
    ++result.box_tests;
    if (frame.template overlap<kTested>(p, pair.first.depth, pair.second.depth)) {
      result.hit = true;
      result.leaf = hint;
      return result;
    }
  }
  constexpr bool kSeparation = kKind == Kind::separation;
  double separation = 0;
  const double floor = kSeparation ? *job.separation / frame.scale_a() : 0;
  descend<K, kTested, kSeparation>(frame, pair.first, pair.second, result, separation, floor,
                                   [&](const Coord& ca, const Coord& cb) { result.leaf = pair.to_caller(ca, cb); });
  if constexpr (kSeparation)
    *job.separation = result.hit || !(separation >= floor) ? 0.0 : separation * frame.scale_a();
  return result;
}

template <class K, Kind kKind>
[[gnu::always_inline]] inline PairTest run_pair(const Job& job) {
  const PairFrame<K> frame(job.pair.first, job.pair.second);
  // collide_all's batched pass tests lanes 0..7 first (half_overlaps<0>),
  // so it takes those 8 in every build.
  constexpr int kSharedAxis = kKind == Kind::all ? kFaceLanes : K::kSharedAxisLanes;
  return frame.shares_axis() && shared_axis_shortcut.load(std::memory_order_relaxed)
             ? test_pair<K, kKind, kSharedAxis>(job, frame)
             : test_pair<K, kKind, kLanes>(job, frame);
}

// One function per kernel build and per kind of test, so that neither
// descent's code is laid out around the other's.
using Runner = PairTest (*)(const Job&);
template <Kind kKind>
PairTest run_portable(const Job& job) {
  return run_pair<Portable, kKind>(job);
}
#ifdef OCTBAKE_X86_KERNELS
// Both return with the upper halves of the vector registers cleared, on every
// path, by an explicit vzeroupper. GCC 12 emits none before the call to
// some_leaf (a function of this file that uses no vector register) and none
// on the exit after it, so the caller's SSE code ran with dirty upper halves,
// which on Intel cores it must merge: every pair test through the containment
// early out took ~150 ns longer (small-on-large pairs slower than in the
// portable build; bench_pair).
template <Kind kKind>
[[gnu::target("avx2,fma"), gnu::flatten]] PairTest run_avx2(const Job& job) {
  const PairTest result = run_pair<Avx2, kKind>(job);
  _mm256_zeroupper();
  return result;
}
template <Kind kKind>
[[gnu::target("avx512f"), gnu::flatten]] PairTest run_avx512(const Job& job) {
  const PairTest result = run_pair<Avx512, kKind>(job);
  _mm256_zeroupper();
  return result;
}
#endif

template <Kind kKind>
Runner runner_of(BoxKernel k) {
#ifdef OCTBAKE_X86_KERNELS
  if (k == BoxKernel::avx512) return run_avx512<kKind>;
  if (k == BoxKernel::avx2) return run_avx2<kKind>;
#endif
  (void)k;
  return run_portable<kKind>;
}

PairTest run(const PlacedTree& a, const PlacedTree& b, const LeafPair* hint, std::vector<LeafPair>* all,
             double* separation = nullptr) {
  check(a);
  check(b);
  static const BoxKernel best = cpu_has(BoxKernel::avx512) ? BoxKernel::avx512
                                : cpu_has(BoxKernel::avx2) ? BoxKernel::avx2
                                                           : BoxKernel::portable;
  const BoxKernel k = chosen_kernel.load(std::memory_order_relaxed);
  const Canonical pair(a, b);
  const BoxKernel use = k == BoxKernel::best ? best : k;
  const Runner runner = all          ? runner_of<Kind::all>(use)
                        : separation ? runner_of<Kind::separation>(use)
                                     : runner_of<Kind::first_hit>(use);
  return runner(Job{pair, hint, all, separation});
}

}  // namespace

void use_shared_axis_shortcut(bool on) { shared_axis_shortcut.store(on, std::memory_order_relaxed); }

bool use_box_kernel(BoxKernel kernel) {
  if (!cpu_has(kernel)) return false;
  chosen_kernel.store(kernel, std::memory_order_relaxed);
  return true;
}

PairTest collide(const PlacedTree& a, const PlacedTree& b) { return run(a, b, nullptr, nullptr); }

PairTest collide(const PlacedTree& a, const PlacedTree& b, double& separation) {
  return run(a, b, nullptr, nullptr, &separation);
}

PairTest collide(const PlacedTree& a, const PlacedTree& b, PairCache& cache) {
  const bool usable = cache.tree_a != nullptr && cache.tree_a == a.tree && cache.tree_b == b.tree &&
                      cache.depth_a == a.depth && cache.depth_b == b.depth &&
                      occupied(*a.tree, a.depth, cache.leaf.a) && occupied(*b.tree, b.depth, cache.leaf.b);
  const PairTest result = run(a, b, usable ? &cache.leaf : nullptr, nullptr);
  cache = result.hit ? PairCache{a.tree, b.tree, a.depth, b.depth, result.leaf} : PairCache{};
  return result;
}

PlacedRoot placed_root(const ObjectTree& tree, const Pose& pose) {
  Pose at_origin = pose;
  at_origin.position.setZero();
  const Aabb& b = tree.bounds();
  return {place(b, at_origin), pose.scale * max_abs_coordinate(b)};
}

bool roots_apart(const PlacedRoot& a, const Eigen::Vector3d& pa, const PlacedRoot& b, const Eigen::Vector3d& pb) {
  // In a's axes: the centre offset t and b's axes (columns of R), world units.
  // Written out: Eigen's 3x3 products stored and reloaded their results.
  const Eigen::Matrix3d &ea = a.box.axes, &eb = b.box.axes;
  const Eigen::Vector3d &ha = a.box.half, &hb = b.box.half;
  const Eigen::Vector3d dp = pb - pa;  // the subtraction collide() starts from
  const Eigen::Vector3d d = dp + (b.box.center - a.box.center);
  double t[3], r[3][3], abs_r[3][3];
  for (int i = 0; i < 3; ++i) {
    t[i] = (ea(0, i) * d[0] + ea(1, i) * d[1]) + ea(2, i) * d[2];
    for (int j = 0; j < 3; ++j) {
      r[i][j] = (ea(0, i) * eb(0, j) + ea(1, i) * eb(1, j)) + ea(2, i) * eb(2, j);
      abs_r[i][j] = std::abs(r[i][j]);
    }
  }
  // collide()'s padding in world units, for either argument order: half
  // extents grow by pad = kRelPad (reaches + offset), so each face radius by
  // at most 4 pad + kAxisPad (the other's half extents summed). Twice that
  // plus rounding (~1e-15 of the same magnitudes) is the margin; the 1-norms
  // bound the 2-norms collide() meets. (The nine edge axes as well cost more
  // than they found on the bundled scenes: collide() tests them anyway.)
  const double magnitude = a.reach + b.reach + dp.cwiseAbs().sum() + d.cwiseAbs().sum();
  const double margin = 10 * kRelPad * magnitude + 2 * kAxisPad * (ha.sum() + hb.sum());
  for (int i = 0; i < 3; ++i)
    if (std::abs(t[i]) > ha[i] + (abs_r[i][0] * hb[0] + abs_r[i][1] * hb[1] + abs_r[i][2] * hb[2]) + margin)
      return true;
  for (int j = 0; j < 3; ++j) {
    const double tb = (r[0][j] * t[0] + r[1][j] * t[1]) + r[2][j] * t[2];  // t on b's axis j
    if (std::abs(tb) > hb[j] + (abs_r[0][j] * ha[0] + abs_r[1][j] * ha[1] + abs_r[2][j] * ha[2]) + margin)
      return true;
  }
  return false;
}

bool roots_apart(const PlacedTree& a, const PlacedTree& b) {
  check(a);
  check(b);
  return roots_apart(placed_root(*a.tree, a.pose), a.pose.position, placed_root(*b.tree, b.pose), b.pose.position);
}

OrientedBox leaf_box(const PlacedTree& p, const BoxCoord& c) {
  return place(p.tree->masks().box_bounds(p.depth, c), p.pose);
}

PairTest collide_all(const PlacedTree& a, const PlacedTree& b, std::vector<LeafPair>& out) {
  return run(a, b, nullptr, &out);
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
