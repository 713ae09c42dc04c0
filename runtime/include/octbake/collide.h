// Conservative pair tests between two posed ObjectTrees.
//
// A simultaneous descent from the roots down to each object's own depth,
// backtracking through every overlapping child pair until one leaf pair
// overlaps (early out). Boxes are compared as oriented boxes (separating axis
// test) in A's frame, from the relative transform computed in double, each box
// padded by a relative epsilon: if the meshes touch, the test reports it at
// every depth pair. Symmetric in a and b: the pair is put in a canonical order
// by content first, so hit and box_tests do not depend on argument order.
//
// Padding: every box half extent grows by 1e-9 times the pair's coordinate
// magnitude in A's frame (largest |local coordinate| of each root, B's scaled
// by sb/sa, plus the offset between the two), far above double rounding and
// far below a depth-12 leaf. A flat tree (zero-thickness axis) becomes a slab.
// Preconditions (asserted): depth in 0..min(tree->loaded_depth(), 12), finite
// pose, scale > 0, unit rotation. No heap allocation.
#pragma once
#include <cstdint>
#include <vector>

#include "octbake/object_tree.h"
#include "octbake/pose.h"
#include "octbake/export.h"

namespace octbake {

struct PlacedTree {
  const ObjectTree* tree = nullptr;
  Pose pose;
  int depth = 0;  // 0..tree->loaded_depth()
};

struct LeafPair {
  BoxCoord a, b;  // at the pair's depths
};

struct PairTest {
  bool hit = false;
  uint64_t box_tests = 0;  // box-box overlap tests done
  // With hit: the overlapping leaf pair that proved it (a in a's tree at
  // a.depth, b in b's tree at b.depth, in the caller's argument order).
  LeafPair leaf;
};

// Box c of `p`'s tree at depth p.depth, placed in the world.
OCTBAKE_API OrientedBox leaf_box(const PlacedTree& p, const BoxCoord& c);

// Does any leaf of a (at a.depth) overlap any leaf of b (at b.depth)?
OCTBAKE_API PairTest collide(const PlacedTree& a, const PlacedTree& b);

// Every overlapping leaf pair (no early out), for response and debugging.
OCTBAKE_API PairTest collide_all(const PlacedTree& a, const PlacedTree& b, std::vector<LeafPair>& out);

}  // namespace octbake
