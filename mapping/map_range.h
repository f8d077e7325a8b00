// map_range.h: the cube of the world a map can hold, and the one check every box of the map's
// interface goes through before its metres become voxel indices: query boxes, extracts, segments,
// cleared boxes and spheres, subscription regions. Beyond +-kMaxVoxelIndex voxels (voxel_types.h)
// no voxel is ever known and the packed keys overflow; a coordinate of 2^31 voxels or more does not
// even convert to an int (a box from 0 to 1e30 m would otherwise wrap to a negative index).
// One check, two uses: a query refuses a box that reaches beyond the range (its answer would count
// voxels no map can hold), a region (clear, subscription) is clipped to it: the voxels beyond cannot
// exist, so clearing or watching them is nothing, and the part within is exactly what the box holds.
// Units: metres, world frame; voxel indices. A voxel belongs to a box when its centre does.
// Threads: pure functions.
#pragma once

#include <cstdint>
#include <string>

#include "mapping/voxel_types.h"

namespace cenote::mapping {

// Half the side of the cube, centred on the origin, that holds every voxel a map of this voxel size
// can know: kMaxVoxelIndex voxels.
double mapRange_m(double voxel_size_m);
// "the map's range, +-N m on each axis", for error messages.
std::string mapRangeText(double voxel_size_m);

// The voxels whose centre lies in a box, clipped to the map's range.
struct BoxVoxels {
  VoxelBox voxels;           // within +-kMaxVoxelIndex on each axis; empty when no centre lies in the box
  bool within_range = true;  // the box lies within +-mapRange_m on each axis (an empty box does)
  // Voxels in `voxels` (0 when empty).
  uint64_t count() const;
};

// @throws Error when a corner is not finite (`what` names the box, e.g. "clear box").
BoxVoxels voxelsOfBox(const Aabb& box_m, double voxel_size_m, const std::string& what);

}  // namespace cenote::mapping
