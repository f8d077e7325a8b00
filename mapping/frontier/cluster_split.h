// cluster_split.h: turns one 26-connected component of frontier voxels into FrontierClusters:
// split in two across its main axis (PCA, through the mean) until no side of a part's bounding
// box exceeds max_extent_m; parts with fewer than min_voxels voxels are dropped.
// Everything is computed from exact integer moments (counts, sums of coordinates and of their
// products, face-direction counts), so the clusters depend only on the set of voxels, never on the
// order a flood fill listed them in: the same clusters whatever grouping of updates found them.
// Units: voxel indices in, metres out (voxel_size_m); world frame. Threads: a plain function.
#pragma once

#include <cstdint>
#include <vector>

#include "mapping/frontier/frontier_map.h"
#include "mapping/voxel_types.h"

namespace cenote::mapping::detail {

// Face neighbours of a voxel, in the bit order of FrontierVoxel::faces: +x, -x, +y, -y, +z, -z.
inline const VoxelIndex kFaceOffsets[6] = {VoxelIndex(1, 0, 0),  VoxelIndex(-1, 0, 0), VoxelIndex(0, 1, 0),
                                           VoxelIndex(0, -1, 0), VoxelIndex(0, 0, 1),  VoxelIndex(0, 0, -1)};

struct FrontierVoxel {
  VoxelIndex ijk;
  uint8_t faces = 0;  // unknown face neighbours, bit i: kFaceOffsets[i]
};

struct SplitParams {
  double voxel_size_m = 0.05;
  double max_extent_m = 2.0;  // > 0
  int min_voxels = 10;        // >= 1
};

// Appends the clusters of `voxels` (one connected component) to `out`, ids taken from next_id
// (incremented per cluster, in a fixed order for a given set of voxels). `voxels` is reordered.
// Indices must lie within +-2^20 (the map's limit). Empty input: no cluster.
void splitComponent(std::vector<FrontierVoxel>& voxels, const SplitParams& params, uint64_t& next_id,
                    std::vector<FrontierCluster>& out);
// The same clusters, faster when `voxels` comes in compact runs (e.g. one block's piece each):
// chunk_ends holds the end index of each run, ascending, the last voxels.size(). A run wholly on
// one side of a splitting plane moves as a whole; only runs the plane cuts are split voxel by voxel.
void splitComponent(std::vector<FrontierVoxel>& voxels, const std::vector<uint32_t>& chunk_ends,
                    const SplitParams& params, uint64_t& next_id, std::vector<FrontierCluster>& out);

}  // namespace cenote::mapping::detail
