// cluster_split.h: turns one 26-connected component of frontier voxels into FrontierClusters:
// split in two across its main axis (PCA, through the mean) until no side of a part's bounding
// box exceeds max_extent_m (counted in whole voxels); parts with fewer than min_voxels voxels are
// dropped. A voxel on a splitting plane goes to the side the axis points to, as Eigen's
// eigenvector sign has it: repeatable (the moments are exact), not mirror-symmetric.
// Everything is computed from exact integer moments (counts, sums of coordinates and of their
// products, face-direction counts), so the clusters depend only on the set of voxels, never on the
// order a flood fill listed them in: the same clusters whatever grouping of updates found them.
// Units: voxel indices in, metres out (voxel_size_m); world frame. Threads: a plain function.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "mapping/frontier/frontier_bits.h"
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

  // The longest box side, in voxels, that does not exceed max_extent_m. Counted in voxels because
  // in metres 6 x 0.1 is 0.6000000000000001 > 0.6: a part exactly max_extent_m wide was split.
  int32_t maxExtentVoxels() const { return static_cast<int32_t>(std::floor(max_extent_m / voxel_size_m + 1e-9)); }
};

// Exact moments of a run of frontier voxels within one block (e.g. one piece), coordinates
// relative to the block's first voxel (0..7): everything the split needs of a run that no plane
// cuts, so that a run kept from an earlier update is not summed again voxel by voxel.
struct RunMoments {
  int32_t n = 0;
  int32_t sum[3] = {0, 0, 0};
  int32_t sum2[6] = {0, 0, 0, 0, 0, 0};  // xx, yy, zz, xy, xz, yz
  int32_t dir[3][3] = {};                // dir[k - 1]: sum of the integer face directions of squared norm k
  int8_t lo[3] = {0, 0, 0};              // bounding box, valid when n > 0
  int8_t hi[3] = {0, 0, 0};
};

// The moments of the voxels `bits` of a block (BlockMask layout), each with its unknown faces
// faces[offsetInBlock] (bit i: kFaceOffsets[i]).
RunMoments blockRunMoments(const BlockMask& bits, const std::array<uint8_t, kBlockVoxels>& faces);

// A run of a component's voxels inside one block (e.g. one piece of the block's frontier). The
// pointers must stay valid during the call.
struct BlockRun {
  BlockIndex block = BlockIndex::Zero();
  const BlockMask* bits = nullptr;                           // the run's voxels
  const std::array<uint8_t, kBlockVoxels>* faces = nullptr;  // unknown faces of the block's voxels
  const RunMoments* moments = nullptr;                       // blockRunMoments(*bits, *faces)
};

// Appends the clusters of `voxels` (distinct voxels, one connected component) to `out`, ids taken
// from next_id (incremented per cluster, in a fixed order for a given set of voxels). Indices must
// lie within +-2^20 (the map's limit). Empty input: no cluster.
void splitComponent(const std::vector<FrontierVoxel>& voxels, const SplitParams& params, uint64_t& next_id,
                    std::vector<FrontierCluster>& out);
// The same for the voxels of `runs` (one connected component, each voxel in one run), without
// listing them: a run wholly on one side of a splitting plane moves as a whole, by its moments;
// only the runs a plane cuts are gone through voxel by voxel.
void splitComponent(const std::vector<BlockRun>& runs, const SplitParams& params, uint64_t& next_id,
                    std::vector<FrontierCluster>& out);

}  // namespace cenote::mapping::detail
