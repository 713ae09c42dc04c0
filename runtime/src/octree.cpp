#include "octbake/octree.h"

#include <bit>

#include "octbake/object_tree.h"
#include "octbake/result.h"

namespace octbake {

const char* to_string(ErrorCode code) {
  switch (code) {
    case ErrorCode::not_found: return "not_found";
    case ErrorCode::io_error: return "io_error";
    case ErrorCode::truncated: return "truncated";
    case ErrorCode::bad_identifier: return "bad_identifier";
    case ErrorCode::unsupported_version: return "unsupported_version";
    case ErrorCode::corrupt: return "corrupt";
    case ErrorCode::decompress_failed: return "decompress_failed";
    case ErrorCode::invalid_argument: return "invalid_argument";
  }
  return "unknown";
}

const char* to_string(Occupancy mode) {
  switch (mode) {
    case Occupancy::surface: return "surface";
    case Occupancy::solid: return "solid";
    case Occupancy::vertices: return "vertices";
  }
  return "unknown";
}

uint64_t OctreeMasks::box_count(int d) const {
  if (d == 0) return 1;
  uint64_t n = 0;
  for (uint8_t m : masks[d - 1]) n += std::popcount(m);
  return n;
}

std::vector<BoxCoord> OctreeMasks::boxes(int d) const {
  std::vector<BoxCoord> level{BoxCoord{}};
  for (int k = 0; k < d; ++k) {
    std::vector<BoxCoord> next;
    next.reserve(box_count(k + 1));
    for (size_t i = 0; i < level.size(); ++i) {
      const uint8_t m = masks[k][i];
      for (uint32_t j = 0; j < 8; ++j) {
        if (!(m & (1u << j))) continue;
        next.push_back({2 * level[i].x + (j & 1u), 2 * level[i].y + ((j >> 1) & 1u), 2 * level[i].z + ((j >> 2) & 1u)});
      }
    }
    level = std::move(next);
  }
  return level;
}

Aabb OctreeMasks::box_bounds(int d, BoxCoord c) const {
  const Eigen::Vector3d size = (bounds.max - bounds.min) / double(uint64_t{1} << d);
  const Eigen::Vector3d lo = bounds.min + size.cwiseProduct(Eigen::Vector3d(c.x, c.y, c.z));
  return {lo, lo + size};
}

ObjectTree::ObjectTree(TreeInfo info, OctreeMasks masks) : info_(std::move(info)), masks_(std::move(masks)) {
  first_child_.resize(masks_.masks.size());
  for (size_t d = 0; d < masks_.masks.size(); ++d) {
    const auto& level = masks_.masks[d];
    auto& first = first_child_[d];
    first.resize(level.size());
    uint32_t next = 0;
    for (size_t i = 0; i < level.size(); ++i) {
      first[i] = next;
      next += std::popcount(level[i]);
    }
  }
}

}  // namespace octbake
