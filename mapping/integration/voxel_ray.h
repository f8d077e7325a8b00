// voxel_ray.h: the voxels a straight segment passes through (3D DDA, Amanatides & Woo 1987), in
// the same order and with the same tie rules as OctoMap's OcTreeBaseImpl::computeRayKeys, so that
// free space carved here matches OctoMap's voxel for voxel up to floating-point rounding.
// Units: metres (world frame) in, voxel indices out. Threads: pure functions.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <limits>

#include "mapping/voxel_types.h"

namespace cenote::mapping {

// floor(x) as an int for |x| < 2^31: truncate, then step down for negative non-integers. The same
// result as std::floor, which without SSE4.1 (the x86-64 baseline) is a longer instruction sequence.
inline int floorToInt(double x) {
  const int i = static_cast<int>(x);
  return i - (x < static_cast<double>(i));
}

inline VoxelIndex toVoxel(const Eigen::Vector3d& p_m, double voxel_size_m) {
  return VoxelIndex(floorToInt(p_m.x() / voxel_size_m), floorToInt(p_m.y() / voxel_size_m),
                    floorToInt(p_m.z() / voxel_size_m));
}

inline Eigen::Vector3d voxelCentre(const VoxelIndex& ijk, double voxel_size_m) {
  return (ijk.cast<double>().array() + 0.5).matrix() * voxel_size_m;
}

// Calls visit(ijk) for each voxel from the voxel of `start_m` towards the voxel of `end_m`.
// With include_end false (OctoMap's free-space rule) the end voxel is not visited, and when start
// and end share a voxel nothing is; with include_end true the end voxel is visited last (a
// segment check). Stops early when visit returns false. Returns false when stopped early.
// The segment must be finite; its length in voxels bounds the work.
template <typename Visit>
bool walkVoxels(const Eigen::Vector3d& start_m, const Eigen::Vector3d& end_m, double voxel_size_m, bool include_end,
                Visit&& visit) {
  const VoxelIndex key_start = toVoxel(start_m, voxel_size_m);
  const VoxelIndex key_end = toVoxel(end_m, voxel_size_m);
  if (key_start == key_end) return include_end ? visit(key_end) : true;
  if (!visit(key_start)) return false;
  Eigen::Vector3d direction = end_m - start_m;
  const double length = direction.norm();
  direction /= length;
  int step[3];
  double t_max[3];
  double t_delta[3];
  VoxelIndex current = key_start;
  for (int i = 0; i < 3; ++i) {
    if (direction[i] > 0.0) {
      step[i] = 1;
    } else if (direction[i] < 0.0) {
      step[i] = -1;
    } else {
      step[i] = 0;
    }
    if (step[i] != 0) {
      const double border = (current[i] + 0.5) * voxel_size_m + step[i] * voxel_size_m * 0.5;
      t_max[i] = (border - start_m[i]) / direction[i];
      t_delta[i] = voxel_size_m / std::fabs(direction[i]);
    } else {
      t_max[i] = std::numeric_limits<double>::max();
      t_delta[i] = std::numeric_limits<double>::max();
    }
  }
  // Every step moves one voxel; a segment cannot cross more than this many faces.
  const long max_steps = 3 * static_cast<long>(length / voxel_size_m) + 6;
  for (long n = 0; n < max_steps; ++n) {
    int dim;
    if (t_max[0] < t_max[1]) {
      dim = t_max[0] < t_max[2] ? 0 : 2;
    } else {
      dim = t_max[1] < t_max[2] ? 1 : 2;
    }
    current[dim] += step[dim];
    t_max[dim] += t_delta[dim];
    if (current == key_end) return include_end ? visit(current) : true;
    if (std::min(std::min(t_max[0], t_max[1]), t_max[2]) > length) {
      // Left the segment without entering the end voxel (it ends on a face or an edge).
      return include_end ? visit(key_end) : true;
    }
    if (!visit(current)) return false;
  }
  return true;
}

}  // namespace cenote::mapping
