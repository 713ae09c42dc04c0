// A decoded ObjectTree, ready for pair tests: occupancy down to loaded_depth()
// plus, per depth, where each box's children start in the next depth.
//
// Thread safety: the const members only read, so one ObjectTree may be shared
// by any number of threads as long as nobody calls push_level()/pop_level()
// on it meanwhile (a LevelCache's trees change only inside its own calls).
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
  // first_child(d, i) for every box i of depth d < loaded_depth(), as one array
  // (for loops that look up many boxes of one depth).
  const uint32_t* first_children(int d) const { return first_child_[d].data(); }

  // Growing and shrinking by levels (streaming, see level_cache.h).
  // Appends the child masks of depth loaded_depth() (one byte per box of that
  // depth, as BakedFile::decode_level returns them), so loaded_depth() grows
  // by one. Precondition (asserted): masks.size() == box_count(loaded_depth()).
  void push_level(std::vector<uint8_t> masks);
  // Drops the deepest loaded level and frees its memory. Precondition: loaded_depth() > 0.
  void pop_level();
  // Memory held for the masks of depth d < loaded_depth(): the mask bytes plus
  // the first-child table, (1 + 4) bytes per box of depth d.
  uint64_t level_bytes(int d) const;
  // The same cost predicted from a header, for level k = 1..info.depth of a
  // file (the masks of depth k-1): what push_level of that level will hold.
  static uint64_t level_bytes(const TreeInfo& info, int k);

 private:
  TreeInfo info_;
  OctreeMasks masks_;
  std::vector<std::vector<uint32_t>> first_child_;
};

}  // namespace octbake
