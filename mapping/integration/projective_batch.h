// projective_batch.h: the voxel updates of one DepthFrame by projective integration, computed
// without reading or locking the map (the projective counterpart of ray_batch.h; the map publishes
// both the same way).
//
// Scheme (as wavemap's and voxblox's projective integrators): instead of marching a ray per pixel,
// every voxel of the blocks inside the camera frustum is projected into the image once.
//  - Free: a voxel whose centre projects into a pixel with depth d, lies in front of the camera at
//    depth z <= d - voxel_size_m (a whole voxel before the surface) and within max_range_m of the
//    camera. A pixel without depth makes its voxels nothing: a stereo hole is not free water.
//  - Hit: the voxel of each pixel's back-projected point within max_range_m (the endpoint voxels of
//    ray integration, so occupied space is the same as with integrate()).
//  Each voxel is updated at most once per frame; occupied wins (free &= ~hit).
// Frustum blocks: the blocks in the bounding box of the frustum up to the largest depth, kept when
// their bounding sphere meets the frustum; they are processed in parallel, each by one thread, so
// the result does not depend on the thread count. Work grows with the frustum volume, not with the
// number of pixels: cheaper than rays for dense images at short range, dearer for long ranges.
// Differences from ray integration: a voxel is carved when its centre's pixel sees past it, rather
// than when some ray crosses it, so free space near silhouettes and grazing surfaces differs by
// about a voxel; the voxel just before each surface (within one voxel) is left unchanged.
// Units: metres, pixels; world frame. Threads: one ProjectiveBatch per writer; build() uses OpenMP.
#pragma once

#include <cstdint>
#include <vector>

#include "mapping/integration/batch_updates.h"
#include "mapping/integration/depth_frame.h"
#include "mapping/integration/endpoint_set.h"
#include "mapping/voxel_types.h"

namespace cenote::mapping {

// The updates (BatchUpdates: block masks, colours) of a depth frame, by projection.
class ProjectiveBatch {
 public:
  // Computes the updates of `frame`, which must already be checked (sizes, finite pose, fx, fy > 0).
  // max_range_m <= 0: unlimited.
  void build(const DepthFrame& frame, double voxel_size_m, double max_range_m, int num_threads);

  // The updates of the last build(), read-only.
  const BatchUpdates& updates() const { return updates_; }
  // Pixels with a depth within range (their hits were recorded).
  size_t numRays() const { return num_hits_; }
  // Frustum blocks whose voxels were projected (for benchmarks).
  size_t numFrustumBlocks() const { return num_frustum_blocks_; }

 private:
  BatchUpdates updates_;
  EndpointSet endpoints_;  // hit voxels with their colour sums
  std::vector<BlockIndex> candidates_;
  std::vector<BlockMasks> candidate_masks_;
  size_t num_hits_ = 0;
  size_t num_frustum_blocks_ = 0;
};

}  // namespace cenote::mapping
