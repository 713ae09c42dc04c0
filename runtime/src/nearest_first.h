// The nearest-first order of a split box's children (collide's descent).
// Internal: in a header of its own so that a test can check it against the
// children's distances.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace octbake {

// The children of a box split at depth d sit at its centre plus
// 2^-d sum_k s_k u_k, s_k = +1 where octant bit k is set, else -1, u_k the
// depth-1 step along the box's axis k (in A's frame). Their squared distances
// to the other box's centre (p, lanes 0..2 of the pair's projections) are
// |p|^2 + 2^(1-d) sum_k s_k w_k, w_k = p . u_k, plus the same term for all 8
// (the u_k are orthogonal). So the nearest child has s_k = -sign(w_k), and
// the others follow by the sum of |w_k| over the axes where they differ
// from it: with the |w_k| sorted, a <= b <= c, the flips in order are
// none, a, b, then a+b and c (either way round), a+c, b+c, a+b+c. One of 12
// orders, picked with no branch and no per-child key.
struct NearestTables {
  uint32_t flips[16];          // [code * 2 + (a + b > c)]: the 8 flip sets in visiting order, 3 bits each
  uint8_t positions[16][256];  // [order][flipped hits]: bit i set iff flip set i is among them
  uint8_t flipped[8][256];     // [nearest][hits]: bit f set iff octant nearest ^ f is in hits
  constexpr NearestTables() : flips{}, positions{}, flipped{} {
    for (int code = 0; code < 8; ++code) {
      // code: bit 0 |w1| < |w0|, bit 1 |w2| < |w0|, bit 2 |w2| < |w1|. The
      // axes by |w|, ascending, ties lower axis first (codes 2 and 5 cannot
      // occur).
      const int c01 = code & 1, c02 = (code >> 1) & 1, c12 = (code >> 2) & 1;
      const int rank[3] = {c01 + c02, (1 - c01) + c12, (1 - c02) + (1 - c12)};
      int sorted[3] = {};
      for (int k = 0; k < 3; ++k) sorted[rank[k] % 3] = k;
      const int x = 1 << sorted[0], y = 1 << sorted[1], z = 1 << sorted[2];
      for (int swap = 0; swap < 2; ++swap) {
        const int order[8] = {0, x, y, swap ? z : x | y, swap ? x | y : z, x | z, y | z, 7};
        uint32_t f = 0;
        for (int i = 0; i < 8; ++i) f |= uint32_t(order[i]) << (3 * i);
        flips[code * 2 + swap] = f;
        for (int h = 0; h < 256; ++h)
          for (int i = 0; i < 8; ++i)
            if (h & (1 << order[i])) positions[code * 2 + swap][h] |= uint8_t(1 << i);
      }
    }
    for (int n = 0; n < 8; ++n)
      for (int h = 0; h < 256; ++h)
        for (int f = 0; f < 8; ++f)
          if (h & (1 << (n ^ f))) flipped[n][h] |= uint8_t(1 << f);
  }
};
inline constexpr NearestTables kNearest;

// The children in `hits` nearest first: `order` holds the 8 octants in
// visiting order (3 bits each), bit i of `left` is set iff order's i-th is
// in hits. w: see NearestTables.
[[gnu::always_inline]] inline void nearest_first(const double (&w)[3], uint32_t hits, uint32_t& order,
                                                 uint32_t& left) {
  const double a0 = std::abs(w[0]), a1 = std::abs(w[1]), a2 = std::abs(w[2]);
  const uint32_t code = uint32_t(a1 < a0) | uint32_t(a2 < a0) << 1 | uint32_t(a2 < a1) << 2;
  // The sizes sorted by min and max, in registers (an array of them indexed
  // by the sort would be stored and reloaded).
  const double lo = std::min(std::min(a0, a1), a2), hi = std::max(std::max(a0, a1), a2);
  const double mid = std::max(std::min(a0, a1), std::min(std::max(a0, a1), a2));
  const uint32_t id = code * 2 + uint32_t(lo + mid > hi);
  const uint32_t nearest = uint32_t(w[0] < 0) | uint32_t(w[1] < 0) << 1 | uint32_t(w[2] < 0) << 2;
  order = kNearest.flips[id] ^ (nearest * 0x249249u);
  left = kNearest.positions[id][kNearest.flipped[nearest][hits]];
}

}  // namespace octbake
