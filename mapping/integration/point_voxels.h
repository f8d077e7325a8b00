// point_voxels.h: the voxel of every point of a batch, floor(p / s) on each axis, bit for bit as
// toVoxel (voxel_ray.h) computes it from the point in double, at the cost of a multiplication
// instead of a division (Highway: one build per instruction set, chosen at run time; the same
// result on every one). RayBatch's endpoint pass: 450k points a frame in `cenote run`.
// Units: metres in, voxel indices out. Threads: a pure function of its arguments.
#pragma once

#include <Eigen/Core>
#include <cstddef>

#include "mapping/voxel_types.h"

namespace cenote::mapping {

// out[i] = toVoxel(points[i].cast<double>(), voxel_size_m) for i < n. voxel_size_m: finite, > 0.
// A coordinate that is not finite, or whose voxel is beyond 2^31, gives what toVoxel gives (which
// is then no voxel: OccupancyMap::checkBatch rejects such points first).
void pointVoxels(const Eigen::Vector3f* points, size_t n, double voxel_size_m, VoxelIndex* out);

}  // namespace cenote::mapping
