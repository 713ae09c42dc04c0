// Internal: the general path of pixel_area, kept callable so a test can hold
// the fast path (whole box in front of the near plane) to it.
#pragma once
#include "octbake/lod.h"

namespace octbake::detail {
// pixel_area computed by clipping every face to the frustum in 3D, whatever
// the box's position.
double pixel_area_clipped(const Camera& camera, const OrientedBox& box);
}  // namespace octbake::detail
