// ObjectTree construction: occupancy (surface / solid / vertices) built top
// down, each triangle handed only to the children it overlaps, so the cost
// follows the occupied boxes rather than 8^depth.
#pragma once
#include "import.h"
#include "octbake/octree.h"

namespace octbake {

// Root = the mesh's axis-aligned bounds (an axis may have zero thickness).
// depth in 1..12.
OctreeMasks build_tree(const Mesh& mesh, int depth, Occupancy mode);

}  // namespace octbake
