// voxel_downsample.h: one point per occupied voxel, the centroid of the points inside (as Open3D's
// voxel_down_sample, which the paper's evaluation script used at 1 mm).
// Units: metres; voxels are axis-aligned cubes of side voxel_m with a corner at the origin.
// Deterministic: output in voxel order (x, then y, then z index), whatever the input order's threads.
// Threads: free function, independent.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace cenote::eval {

// @param voxel_m side of a voxel; 0 returns the points unchanged.
// @throws cenote::Error when voxel_m is negative or not finite, or when a coordinate divided by
//         voxel_m does not fit a 64-bit voxel index.
std::vector<Eigen::Vector3f> voxelDownsample(const std::vector<Eigen::Vector3f>& points, double voxel_m);

}  // namespace cenote::eval
