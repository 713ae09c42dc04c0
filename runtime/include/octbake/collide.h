// Conservative pair tests between two posed ObjectTrees.
//
// How the descent works. Both trees are compared in A's local frame (the
// relative transform is computed once per pair, in double, positions
// subtracted first). A pair of boxes is tested with the 15-axis separating
// axis test of two oriented boxes; the descent starts at the two roots and,
// at every overlapping box pair that is not yet a leaf pair, splits ONE box:
// the larger one (half diagonal in A's units; a tree already at its depth
// cannot split). Which box splits depends only on the two depths, so each
// level of the descent is worked out once per pair, when the descent first
// reaches it (most pair tests end after a few). All occupied children of the
// split box are tested against the other box in one go, and the overlapping
// ones are visited nearest first (distance between box centres), depth first,
// with full backtracking. The first overlapping leaf pair ends the descent
// (early out): that pair proves the hit and is reported (children that are leaf
// pairs are reported where they are tested, the nearest one, without being
// visited). So a small object against a large one walks down the large tree
// first, and the pairs most likely to touch are tried first.
// One more early out: when the other box is already a leaf and holds the box
// about to split whole (with a margin of one pad), any occupied leaf below
// overlaps it, so the first one found (lowest octants first) proves the hit.
// box_tests counts each child box tested, the root pair, a cached pair
// (PairCache) and a containment proof (one each); a containment check that
// fails reuses the pair's projections and is not counted.
// collide_all has no early out, so the order of its visits cannot change which
// box pairs it tests: it expands the same pairs (the same split schedule, every
// overlapping child) breadth first, a batch of up to 32 pairs of a level at a
// time: their occupied children are listed, tested in one flat loop without
// branching on the results (on lanes 0..7; those that pass are tested on
// lanes 8..15 as they are taken in order), and the overlapping ones become
// the next level's batch. A level's pairs are all expanded before the next
// batch of the level above, so memory stays bounded (at most 256 pairs a
// level, kept per thread between calls) and leaf pairs come out in
// depth-first order, children in octant order. Its box_tests are those of a depth-first walk over the same
// pairs.
//
// Box tests at memory speed. The 8 children of a box share its axes and sit at
// its centre plus or minus a quarter of its size, so a child's projection on
// each of the 15 axes is its parent's plus a signed sum of three terms,
// precomputed per depth for the pair. A box pair carries its 15 projections
// (16 lanes, one idle); testing a child is 16 additions, absolute values and
// comparisons against precomputed radii (collide_all's offsets are scaled to
// each depth beforehand, collide's by a power of two in the test: exact
// either way; double precision; AVX-512 or AVX2 where the CPU has them, plain
// C++ otherwise; all give identical bits). Nothing is stored for a child that
// is tested: collide's descent keeps one record per path level (the pair open
// there and its overlapping children still to visit), and both compute a
// child's projections from its parent's when they visit it (the same sums as
// the test). The whole pair test is compiled once per ISA with its kernel
// inlined and the build is chosen once per pair.
//
// Why it is conservative. If the meshes touch at a point x, x lies in an
// occupied leaf box of each tree (the occupancy is conservative) and so in
// every ancestor of both leaves. Every box pair on the path of ancestors
// therefore overlaps, and the descent tests every child of every overlapping
// pair it splits, so it reaches an overlapping leaf pair (perhaps another one
// first). Ordering only changes which hit is found first, never whether; the
// containment early out stops only where a leaf pair is known to overlap.
// Rounding cannot turn an overlap into a separation: every box half extent
// grows by 1e-9 times the pair's coordinate magnitude M in A's frame (largest
// |local coordinate| of each root, B's scaled by sb/sa, plus the offset
// between the two), and |R| gets 1e-9 added on the cross axes (Gottschalk's
// guard for near-parallel edges); the projections accumulate at most a few
// dozen roundings of M (1e-14 M), far below that padding, which itself stays
// far below a depth-12 leaf. A padded child box lies inside its padded
// parent, so coarser depths never report less than finer ones. A flat tree
// (zero-thickness axis) becomes a slab.
//
// Symmetric in a and b: the pair is put in a canonical order by content first,
// so hit, box_tests and leaf (mapped back to the caller's order) do not depend
// on argument order. Deterministic: the same inputs give the same counts.
// Preconditions (asserted): depth in 0..min(tree->loaded_depth(), 12), finite
// pose, scale > 0, unit rotation. No heap allocation (about 45 KB of stack).
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
  uint64_t box_tests = 0;  // box-box overlap tests done (one per child box tested)
  // With hit: the overlapping leaf pair that proved it (a in a's tree at
  // a.depth, b in b's tree at b.depth, in the caller's argument order).
  LeafPair leaf;
};

// Temporal coherence: what the caller keeps per candidate pair between frames
// (default-constructed = empty). Holds the leaf pair that proved the last hit
// and the trees and depths it belongs to, in the argument order of the call
// that stored it.
struct PairCache {
  const ObjectTree* tree_a = nullptr;  // nullptr: empty
  const ObjectTree* tree_b = nullptr;
  int depth_a = -1, depth_b = -1;
  LeafPair leaf;
};

// Box c of `p`'s tree at depth p.depth, placed in the world.
OCTBAKE_API OrientedBox leaf_box(const PlacedTree& p, const BoxCoord& c);

// Does any leaf of a (at a.depth) overlap any leaf of b (at b.depth)?
OCTBAKE_API PairTest collide(const PlacedTree& a, const PlacedTree& b);

// collide() trying the cached leaf pair first. The cached pair is used only if
// the cache holds the same trees and depths in this argument order and both
// boxes are still occupied; it then costs one box test and, if the two boxes
// still overlap, proves the hit by itself (it is a real occupied leaf pair, so
// never a false hit). Otherwise the full descent runs as in collide() (its
// box tests added to the one spent). The cache ends up holding the proving
// leaf pair of a hit, or empty after a miss. The hit is always collide()'s;
// box_tests and leaf may differ (another overlapping leaf pair may prove it).
OCTBAKE_API PairTest collide(const PlacedTree& a, const PlacedTree& b, PairCache& cache);

// collide(), and after a miss its separation: how far b may be translated
// relative to a (world units, any direction) with collide() still finding no
// contact, the two trees, depths, rotations and scales kept bit for bit
// (every box pair the descent found separated stays so, with a slack for the
// padding following the positions and for rounding). `separation` goes in as
// the least worth knowing (>= 0): below it, its working out stops and 0 comes
// back. 0 after a hit; infinite if no leaf pair lies under the roots. It costs
// more than collide() (each separated child's projections again until the
// floor is passed); CollisionWorld asks for it for pairs that moved without
// turning, to answer their next frames without a test.
OCTBAKE_API PairTest collide(const PlacedTree& a, const PlacedTree& b, double& separation);

// A tree's root box under a pose, apart from the pose's position: what
// roots_apart reads, worked out once per rotation and scale (CollisionWorld
// keeps one per object).
struct PlacedRoot {
  OrientedBox box;   // place(tree bounds, pose) with the position left out
  double reach = 0;  // scale times the largest |coordinate| of the tree's bounds
};
OCTBAKE_API PlacedRoot placed_root(const ObjectTree& tree, const Pose& pose);

// Are the root boxes of a and b (at positions pa, pb) apart on one of their
// six face axes by more than collide()'s padding and rounding? Then collide()
// of the two trees at these poses, with an empty cache, is a miss after its
// one root box test at any depths: a caller that picks the depths first can
// skip them. A fraction of that test's set-up; false says nothing.
OCTBAKE_API bool roots_apart(const PlacedRoot& a, const Eigen::Vector3d& pa, const PlacedRoot& b,
                             const Eigen::Vector3d& pb);
// The same for two placed trees (their depths are not read).
OCTBAKE_API bool roots_apart(const PlacedTree& a, const PlacedTree& b);

// Every overlapping leaf pair (no early out), for response and debugging.
OCTBAKE_API PairTest collide_all(const PlacedTree& a, const PlacedTree& b, std::vector<LeafPair>& out);

// ---- Reference implementation: for tests and benchmarks only -------------
// The plain scalar descent this library shipped before: both trees split at
// once, child pairs in fixed octant order, one scalar separating axis test per
// box pair, same padding. Same hits (and for collide_all_reference the same
// leaf pairs) as collide / collide_all; box_tests and the proving leaf pair
// differ. Kept beside the fast path to check it and to measure it against.
OCTBAKE_API PairTest collide_reference(const PlacedTree& a, const PlacedTree& b);
OCTBAKE_API PairTest collide_all_reference(const PlacedTree& a, const PlacedTree& b, std::vector<LeafPair>& out);

// Tests and benchmarks only: which build of the box-test kernel collide() and
// collide_all() run, process-wide (best: the widest the CPU has). All builds
// give identical bits. Returns false, changing nothing, if the CPU lacks it.
enum class BoxKernel { best, portable, avx2, avx512 };
OCTBAKE_API bool use_box_kernel(BoxKernel kernel);

// Tests and benchmarks only: whether a pair whose boxes share an axis exactly
// (both unrotated, or turned about the same axis: upright objects that only
// yaw) is tested on the six face axes alone (on, the default), which then
// separate every box pair the nine edge axes would, or on all fifteen.
// Process-wide. Off exists to compare the two.
OCTBAKE_API void use_shared_axis_shortcut(bool on);

}  // namespace octbake
