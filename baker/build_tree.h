// ObjectTree construction: occupancy (surface / solid / vertices) built top
// down, each triangle handed only to the children it overlaps, so the cost
// follows the occupied boxes rather than 8^depth.
#pragma once
#include "import.h"
#include "octbake/octree.h"

namespace octbake {

// Root = the mesh's axis-aligned bounds over all positions (an axis may have
// zero thickness: its boxes stay flat). depth in 1..12 (asserted); the mesh
// must have at least one position.
//
// Modes (docs/interface.md section 2):
//  - surface: a box is occupied when a triangle overlaps the closed box grown
//    by occupancy_pad(bounds) (exact separating-axis test, degenerate
//    triangles included);
//  - solid: surface plus the interior enclosed by it. Empty space is flood
//    filled from outside the grid through 6-connected empty boxes of depth
//    min(depth, 8); boxes deeper than 8 are interior when their depth-8
//    ancestor is wholly interior (interior space sharing a depth-8 box with
//    the surface is left to the surface boxes). An open mesh whose holes are
//    wider than a fill box gives the same tree as surface;
//  - vertices: the thesis's rule, a box is occupied when it holds a vertex.
//    Boxes are closed (grown by the same pad), so a vertex on a face, edge or
//    corner shared by boxes occupies all of them.
// Single threaded and deterministic: the same mesh gives the same masks.
OctreeMasks build_tree(const Mesh& mesh, int depth, Occupancy mode);

// The margin build_tree grows every box by so rounding never drops a touched
// box: 1e-9 of the largest extent plus a few ulp of the largest coordinate.
double occupancy_pad(const Aabb& bounds);

// The flood-fill depth cap of solid mode.
constexpr int kSolidFillDepth = 8;

}  // namespace octbake
