// The WorldTree: a fixed octree over the world bounds whose leaves hold object
// ids; objects sharing a leaf are candidate pairs. An object may sit in several
// leaves. Objects (partly) outside the bounds also go to an overflow set that
// is paired with everything, so nothing is ever dropped.
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include "octbake/octree.h"

namespace octbake {

class WorldTree {
 public:
  WorldTree(const Aabb& world, int depth);

  // Inserts object `id` or moves it to `box`. Returns true when its leaf set
  // (or overflow membership) changed, false when nothing needed re-inserting.
  bool update(uint32_t id, const Aabb& box);
  void remove(uint32_t id);

  // Candidate pairs (a < b), each once, sorted ascending.
  void candidate_pairs(std::vector<std::pair<uint32_t, uint32_t>>& out) const;

  int depth() const { return depth_; }
  const Aabb& bounds() const { return world_; }
  uint64_t reinsertions() const { return reinsertions_; }

 private:
  struct Entry;
  Aabb world_;
  int depth_;
  uint64_t reinsertions_ = 0;
  // Implementation state lives in world_tree.cpp (owned by the runtime).
  std::vector<std::vector<uint32_t>> cells_;  // leaf -> ids
  std::vector<std::array<uint32_t, 6>> ranges_;  // id -> leaf range [lo, hi) per axis
  std::vector<uint8_t> present_, overflow_;
};

}  // namespace octbake
