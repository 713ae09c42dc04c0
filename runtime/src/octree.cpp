#include "octbake/octree.h"

#include <bit>
#include <cassert>

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
  std::vector<std::vector<uint8_t>> levels = std::move(masks_.masks);
  masks_.masks.clear();
  for (auto& level : levels) push_level(std::move(level));
}

void ObjectTree::push_level(std::vector<uint8_t> masks) {
  assert(masks.size() == box_count(loaded_depth()));
  std::vector<uint32_t> first(masks.size());
  uint32_t next = 0;
  for (size_t i = 0; i < masks.size(); ++i) {
    first[i] = next;
    next += std::popcount(masks[i]);
  }
  masks_.masks.push_back(std::move(masks));
  first_child_.push_back(std::move(first));
}

void ObjectTree::pop_level() {
  assert(loaded_depth() > 0);
  masks_.masks.pop_back();
  first_child_.pop_back();
}

uint64_t ObjectTree::level_bytes(int d) const {
  return masks_.masks[d].size() * sizeof(uint8_t) + first_child_[d].size() * sizeof(uint32_t);
}

uint64_t ObjectTree::level_bytes(const TreeInfo& info, int k) {
  return info.box_count[k - 1] * (sizeof(uint8_t) + sizeof(uint32_t));
}

}  // namespace octbake
