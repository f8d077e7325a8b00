// reference_cluster_split.h: a slow, independent reference for how FrontierMap splits one
// 26-connected component of frontier voxels into clusters (the rule mapping/frontier/
// cluster_split.h documents), written from that rule voxel by voxel with none of the production
// code: no block runs or moments, no box classification of chunks. Tests compare FrontierMap's
// clusters with these.
// The rule: a part with fewer than min_voxels voxels is dropped; a part of at least 2 voxels whose
// longest bounding box side exceeds max_extent_m, counted in whole voxels (more than
// floor(max_extent_m / voxel_size_m) of them: a side of exactly max_extent_m stays), is cut by the
// plane through its mean across its main axis (the eigenvector of the largest eigenvalue of its
// covariance, as Eigen::SelfAdjointEigenSolver returns it), a voxel going to the low part when
// (n v - sum) . axis < 0 (n times (v - mean) . axis; a voxel on the plane goes to the other part:
// which part that is follows the sign Eigen gives the axis, so mirror images need not split
// alike), and both parts are split again; a part the plane does not cut (one side empty) is kept
// whole.
// Units: voxel indices in; metres out (voxel_size_m); world frame. Threads: plain functions.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "mapping/voxel_types.h"

namespace cenote::mapping::test {

// Face neighbours in the bit order of a frontier voxel's `faces`: +x, -x, +y, -y, +z, -z.
inline const VoxelIndex kReferenceFaceOffsets[6] = {VoxelIndex(1, 0, 0),  VoxelIndex(-1, 0, 0), VoxelIndex(0, 1, 0),
                                                    VoxelIndex(0, -1, 0), VoxelIndex(0, 0, 1),  VoxelIndex(0, 0, -1)};

struct ReferenceVoxel {
  VoxelIndex ijk = VoxelIndex::Zero();
  uint8_t faces = 0;  // unknown face neighbours, bit i: kReferenceFaceOffsets[i]
};

struct ReferenceCluster {
  std::vector<ReferenceVoxel> voxels;                    // in the order of the component given
  Eigen::Vector3d centroid_m = Eigen::Vector3d::Zero();  // mean of the voxel centres
  Aabb bounds_m;                                         // of the voxels (their faces)
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();   // normalised sum of the voxels' unit
                                                         // directions into the unknown (zero if none)
};

// The clusters of one component (distinct voxels, 26-connected), appended to `out`. Coordinates
// must stay within +-2^20 and the component below 2^20 voxels (the sums are then exact in int64).
void referenceSplitComponent(const std::vector<ReferenceVoxel>& component, double voxel_size_m, double max_extent_m,
                             int min_voxels, std::vector<ReferenceCluster>& out);

}  // namespace cenote::mapping::test
