#include "octbake/pose.h"

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace octbake {
namespace {

// std::nextafter(x, +inf) inline (the libm call was a tenth of a frame with
// many spinning objects): the next double up, for every x.
#if !defined(__SSE2__)
double next_up(double x) {
  if (std::isnan(x) || x == std::numeric_limits<double>::infinity()) return x;
  if (x == 0) return std::numeric_limits<double>::denorm_min();
  const uint64_t bits = std::bit_cast<uint64_t>(x);
  return std::bit_cast<double>(x > 0 ? bits + 1 : bits - 1);
}
#else
// The same on two lanes without a branch (six scalar ones were most of
// world_bounds, run per spinning object per frame): the bit pattern steps
// +1 for 0 < x < inf, -1 for x < 0 (-inf included), zeros become the
// smallest denormal, and NaN and +inf stay.
__m128d next_up(__m128d x) {
  const __m128d zero = _mm_setzero_pd();
  const __m128d up = _mm_and_pd(_mm_cmpgt_pd(x, zero), _mm_cmplt_pd(x, _mm_set1_pd(std::numeric_limits<double>::infinity())));
  const __m128d down = _mm_cmplt_pd(x, zero);
  // The masks are -1 where set: down - up is the step.
  const __m128i step = _mm_sub_epi64(_mm_castpd_si128(down), _mm_castpd_si128(up));
  const __m128d stepped = _mm_castsi128_pd(_mm_add_epi64(_mm_castpd_si128(x), step));
  const __m128d is_zero = _mm_cmpeq_pd(x, zero);
  return _mm_or_pd(_mm_andnot_pd(is_zero, stepped),
                   _mm_and_pd(is_zero, _mm_set1_pd(std::numeric_limits<double>::denorm_min())));
}
#endif

}  // namespace

OrientedBox place(const Aabb& local, const Pose& pose) {
  OrientedBox box;
  box.center = pose.apply(0.5 * (local.min + local.max));
  box.axes = rotation_matrix(pose.rotation);
  box.half = (0.5 * pose.scale) * (local.max - local.min).cwiseAbs();
  return box;
}

Aabb world_bounds(const OrientedBox& box) {
  // Extent along each world axis; the relative grow absorbs the rounding of
  // the rotation matrix and of this sum, one ulp outwards the rounding of +/-.
  Eigen::Vector3d extent = box.axes.cwiseAbs() * box.half;
  extent *= 1.0 + 1e-12;
  Aabb out;
#if defined(__SSE2__)
  // next_down(x) = -next_up(-x): the six bounds as three pairs of next_up,
  // paired in registers (scalar stores read back as pairs would stall).
  const Eigen::Vector3d lo = box.center - extent, hi = box.center + extent;
  alignas(16) double v[6];
  _mm_store_pd(v, next_up(_mm_set_pd(-lo[1], -lo[0])));
  _mm_store_pd(v + 2, next_up(_mm_set_pd(hi[0], -lo[2])));
  _mm_store_pd(v + 4, next_up(_mm_set_pd(hi[2], hi[1])));
  out.min = {-v[0], -v[1], -v[2]};
  out.max = {v[3], v[4], v[5]};
#else
  for (int i = 0; i < 3; ++i) {
    out.min[i] = -next_up(-(box.center[i] - extent[i]));
    out.max[i] = next_up(box.center[i] + extent[i]);
  }
#endif
  return out;
}

}  // namespace octbake
