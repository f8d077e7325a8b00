// ray_batch.h: the voxel updates of one PointBatch, computed without reading or locking the map.
//
// Scheme (the one OctoMap's insertPointCloud uses with discretize on, made fast):
//  1. Endpoints are deduplicated per voxel (within each chunk, see 4.; the last voxel is cached, as
//     neighbouring pixels mostly share one); each ray then goes from the origin to the centre of its
//     endpoint voxel. 270k stereo points at 5 cm fall into a few tens of thousands of voxels, so
//     this removes most of the work and changes nothing a 5 cm map can represent. The colour of an
//     endpoint voxel is the mean of its points' colours. The points' voxels come from a SIMD kernel
//     (point_voxels.h) that gives toVoxel's bits at a multiplication's cost.
//  2. Rays are marched with a 3D DDA (the voxels of the segment from the origin to the endpoint
//     voxel's centre, ties as OctoMap's computeRayKeys) into per-block bit masks (8x8x8 voxels =
//     512 bits per mask, a free mask and a hit mask), looked up only when the ray crosses into
//     another block (about every 8 steps), through a dense index of the blocks in the chunk's box
//     (BatchUpdates::setWindow; the hash table beyond it). Each ray is walked by the instance of
//     the walk for its octant (the signs of its steps as constants). The masks are the per-batch
//     visited set, so each voxel is updated at most once per batch; a voxel both crossed and hit
//     is a hit (occupied wins: free &= ~hit). The DDA takes the t of each voxel face it crosses
//     from one formula of the face's index (not a running sum), so walking a ray from its end back
//     to the origin visits exactly the voxels of the walk from the origin, whatever the rounding.
//  3. Early stop (stop_run > 0): rays from one origin overlap heavily (a 283k-point frame of
//     bench/map_bench at 5 cm makes 6.6M DDA steps for 0.51M distinct voxels), so each ray is
//     marched from its end back towards the origin and stops after stop_run consecutive voxels
//     already carved by earlier rays: from there those rays have carved (nearly) the same path to
//     the origin. Every voxel made free lies on the ray's exact path (2.), so the free set is a
//     subset of stop_run 0's (OctoMap's): early stopping can leave a voxel unknown, never make one
//     free that no ray crosses. Rays that cross at one voxel and part again make a single carved
//     voxel a poor signal: in image order, stop_run 1 lost 13 % of the free voxels, 4 lost 0.8 %
//     (and left holes inside rooms that become false frontiers,
//     tests/mapping/frontier/frontier_map_test.cpp), 16 lost 0.04 %. A chunk's rays are marched
//     in 16 interleaved passes over its endpoints (ray_batch.cpp): the rays before one then lie on
//     all sides of it, not only in the image rows above, so it meets the carved path sooner. The
//     default run of 32 leaves fewer voxels unknown than image order with 16 did (0.032 % on
//     tests/mapping/integration/octomap_equivalence_test.cpp's survey, 0.11 % on its laser scan,
//     where 16 in image order left 0.04 % and 0.25 %) in 35 % of whole rays' steps (2.34M a frame
//     in bench/map_bench; 16 in image order: 3.08M, 46 %).
//     stop_run 0 marches every ray whole from the origin, like OctoMap's computeRayKeys:
//     OctoMap's voxel sets (up to rounding: OctoMap casts from float coordinates, 3e-5 of the
//     free voxels differ on the laser scan of tests/mapping/integration/octomap_equivalence_test.cpp).
//  4. Points are split into a fixed number of chunks (consecutive points: image bands), each
//     deduplicated and marched into private masks by any thread and then OR-ed: the map is the same
//     for any thread count (early stopping depends only on the chunk's own rays). An endpoint voxel
//     spanning two bands is marched by both (the union is unchanged); its colour is merged. Each
//     chunk carves the trunk of its rays near the camera afresh, and its early stops see only its
//     own rays: 8 chunks march 10 % fewer steps than 16, and still balance 2 threads (the top
//     band, the far floor, takes about 40 % of the steps, which bounds 4 threads' speed-up to 2.5).
// No coarse clearing: carving a ray's far stretch by 2x2x2 cells (all 8 voxels of a cell it
// crosses made free) takes a third fewer instructions in bench/map_bench, but makes free voxels no
// ray crossed, which a planner takes as safe: 4 % more than OctoMap's in the bench at 5 cm, 7 % at
// 0.1 m, 74 % on octomap_equivalence_test's laser scan at 0.1 m.
// Range rule: an endpoint centre farther than max_range_m carves free space to max_range_m along
// its ray and records no hit (OctoMap's rule). Rays end at the endpoint voxel, exclusive.
// Units: metres, world frame. Threads: one RayBatch per writer; build() uses OpenMP internally.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "common/point_batch.h"
#include "mapping/integration/batch_updates.h"
#include "mapping/integration/endpoint_set.h"
#include "mapping/voxel_types.h"

namespace cenote::mapping {

// The updates (BatchUpdates: block masks, colours) of a batch of rays.
class RayBatch {
 public:
  static constexpr int kRayChunks = 8;  // early stop; fixed so that results ignore the thread count (4.)

  // Computes the updates of `batch`. The batch must already be checked (finite, in range).
  // stop_run: see 3. above; 0 marches every ray whole (OctoMap's voxel sets); any stop_run gives
  // a subset of stop_run 0's free voxels and the same hits.
  void build(const PointBatch& batch, double voxel_size_m, double max_range_m, int num_threads, int stop_run);

  // The updates of the last build(), read-only.
  const BatchUpdates& updates() const { return updates_; }
  // Rays cast: the unique endpoint voxels of each chunk, summed.
  size_t numRays() const { return num_rays_; }
  // Voxels the rays visited (DDA steps), summed over the chunks: the work of the march. With
  // stop_run 0 the chunks are one per thread, so this depends on the thread count (the map does not).
  size_t numSteps() const { return num_steps_; }

 private:
  // Scratch of one chunk of points.
  struct Chunk {
    std::vector<VoxelIndex> voxels;  // the voxel of each point (pointVoxels)
    EndpointSet endpoints;           // unique endpoint voxels, in point order
    BatchUpdates updates;            // masks only
    size_t steps = 0;                // voxels its rays visited
    bool done = false;               // marched and united (this build)
  };

  BatchUpdates updates_;
  EndpointSet endpoints_;  // colour merge over the chunks
  std::vector<Chunk> chunks_;
  size_t num_rays_ = 0;
  size_t num_steps_ = 0;
};

}  // namespace cenote::mapping
