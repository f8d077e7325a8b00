// integration_peers.h: the integration rows of map_bench, ours beside OctoMap's insertPointCloud
// on the same frames in the same run, each as wall and CPU time per frame; and the frames written
// out as depth images for bench/open3d_bench.py (Open3D's TSDF integration of the same views).
// CPU time is what load disturbs least: ours is the process's (all threads; OMP_WAIT_POLICY
// passive, main() sees to it, so that idle OpenMP threads sleep rather than spin), OctoMap's its
// thread's (it has one).
// Threads: each function runs its integration on the caller's thread (ours with its OpenMP team).
#pragma once

#include <octomap/OcTree.h>

#include <memory>
#include <string>
#include <vector>

#include "common/point_batch.h"
#include "mapping/integration/depth_frame.h"
#include "mapping/occupancy_map.h"

namespace cenote::bench {

struct IntegrationTime {
  double wall_ms = 0.0;  // per frame
  double cpu_ms = 0.0;   // per frame
};

// The frames into a fresh map of `config` after one warm-up frame (scratch allocation, then
// reset), timed over the frames. @return the times; `map` is the map after the frames.
IntegrationTime timeOurIntegration(const std::vector<PointBatch>& frames, const mapping::MapConfig& config,
                                   std::unique_ptr<mapping::OccupancyMap>& map);

// The same views as depth images through integrateDepth, likewise.
IntegrationTime timeProjectiveIntegration(const std::vector<mapping::DepthFrame>& frames, const mapping::MapConfig& config,
                                          std::unique_ptr<mapping::OccupancyMap>& map);

// OctoMap's insertPointCloud (discretize on) of the frames into `tree`, with hit 0.7, miss 0.4
// and clamping 0.12 / 0.97 as our defaults (set here), `max_range_m` as ours.
IntegrationTime timeOctomapIntegration(const std::vector<PointBatch>& frames, double max_range_m, octomap::OcTree& tree);

// Writes `frames` into `dir` (created) for bench/open3d_bench.py: frames.txt (one line "camera
// width height fx fy cx cy", "voxel_m v", "max_range_m r", then per frame "frame FILE" and the 12
// numbers of T_world_cam's first three rows) and per frame FILE, its depth in metres as raw
// little-endian float32, row-major, 0 where there is none. @throws cenote::Error when a file
// cannot be written.
void writeDepthFrames(const std::string& dir, const std::vector<mapping::DepthFrame>& frames, double voxel_m,
                      double max_range_m);

}  // namespace cenote::bench
