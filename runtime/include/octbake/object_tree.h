// A decoded ObjectTree, ready for pair tests: occupancy down to loaded_depth()
// plus, per depth, where each box's children start in the next depth.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "octbake/format.h"
#include "octbake/octree.h"
#include "octbake/export.h"

namespace octbake {

class OCTBAKE_API ObjectTree {
 public:
  ObjectTree() = default;
  // `masks` holds depths 0..loaded-1 (masks.depth() == loaded depth).
  ObjectTree(TreeInfo info, OctreeMasks masks);

  const TreeInfo& info() const { return info_; }
  const Aabb& bounds() const { return masks_.bounds; }
  int loaded_depth() const { return masks_.depth(); }
  const OctreeMasks& masks() const { return masks_; }
  uint64_t box_count(int depth) const { return masks_.box_count(depth); }
  // Child mask of box i at depth d < loaded_depth().
  uint8_t mask(int d, uint32_t i) const { return masks_.masks[d][i]; }
  // Index in depth d+1 of box i's first child (children are consecutive).
  uint32_t first_child(int d, uint32_t i) const { return first_child_[d][i]; }

 private:
  TreeInfo info_;
  OctreeMasks masks_;
  std::vector<std::vector<uint32_t>> first_child_;
};

}  // namespace octbake
