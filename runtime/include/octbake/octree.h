// The ObjectTree's occupancy, shared by the baker (which builds it) and the
// runtime (which decodes it). docs/interface.md section 1; encoding in schema/.
#pragma once
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <vector>
#include "octbake/export.h"

namespace octbake {

struct Aabb {
  Eigen::Vector3d min{0, 0, 0};
  Eigen::Vector3d max{0, 0, 0};
  bool operator==(const Aabb& o) const { return min == o.min && max == o.max; }
};

// The largest |coordinate| of the box: the magnitude that rounding errors of
// coordinates in it scale with (paddings are set from it).
inline double max_abs_coordinate(const Aabb& b) {
  return std::max(b.min.cwiseAbs().maxCoeff(), b.max.cwiseAbs().maxCoeff());
}

// Closed boxes: touching counts.
inline bool overlaps(const Aabb& a, const Aabb& b) {
  return (a.min.array() <= b.max.array()).all() && (b.min.array() <= a.max.array()).all();
}

enum class Occupancy : uint8_t { surface = 0, solid = 1, vertices = 2 };
inline constexpr Occupancy kOccupancies[] = {Occupancy::surface, Occupancy::solid, Occupancy::vertices};
OCTBAKE_API const char* to_string(Occupancy mode);

// Child octant j of a box: x offset = bit 0, y = bit 1, z = bit 2.
// (Format-fixing: the schema's level encoding uses this order.)
constexpr int kOctantX = 1, kOctantY = 2, kOctantZ = 4;

// Integer box address at one depth: coordinates in [0, 2^depth) per axis.
struct BoxCoord {
  uint32_t x = 0, y = 0, z = 0;
  bool operator==(const BoxCoord&) const = default;
};

// Occupancy of one tree, breadth first. masks[d][i] is the child-occupancy
// byte of the i-th occupied box at depth d, boxes in Morton order, for
// d = 0..depth()-1. The root (depth 0) is always occupied; the boxes of depth
// d+1 are the set bits of masks[d] in order. A child bit is set only under an
// occupied parent, so conservative nesting holds by construction.
struct OCTBAKE_API OctreeMasks {
  Aabb bounds;  // the root box: the mesh's local axis-aligned bounds
  std::vector<std::vector<uint8_t>> masks;

  int depth() const { return static_cast<int>(masks.size()); }
  // Occupied boxes at depth d (0..depth()).
  uint64_t box_count(int d) const;
  // Addresses of the occupied boxes at depth d, in Morton order.
  std::vector<BoxCoord> boxes(int d) const;
  // The local-space extent of box c at depth d (zero-thickness axes stay flat).
  Aabb box_bounds(int d, BoxCoord c) const;
  bool operator==(const OctreeMasks&) const = default;
};

}  // namespace octbake
