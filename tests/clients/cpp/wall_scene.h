// wall_scene.h: the analytic scene of the client end-to-end tests and the server benchmark: a
// wall of points at voxel centres seen from a known origin, so that which voxels are occupied,
// free and unknown is known exactly; and its copy as the in-process map's PointBatch.
// Units: metres, world frame; voxel size 0.05 m (the server's default), grid as
// mapping/voxel_types.h: voxel i covers [0.05 i, 0.05 (i + 1)).
// Threads: pure functions.
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "clients/cpp/client_types.h"
#include "common/point_batch.h"

namespace cenote::client::test {

inline constexpr double kVoxel_m = 0.05;
// Centre of voxel i along an axis.
inline double centre(int i) { return (i + 0.5) * kVoxel_m; }
inline Eigen::Vector3d centre(int i, int j, int k) { return {centre(i), centre(j), centre(k)}; }

// The wall: voxels x = kWallX, y and z in [kWallMin, kWallMax] (40 x 40 = 1600 voxels), one point
// at each centre, seen from the centre of voxel (0, 0, 0).
inline constexpr int kWallX = 40;  // x centre 2.025 m
inline constexpr int kWallMin = -20;
inline constexpr int kWallMax = 19;
inline const Eigen::Vector3d kOrigin_m = centre(0, 0, 0);

inline PointBatch wallBatch(int wall_x = kWallX, const Eigen::Vector3d& origin_m = kOrigin_m, double t_s = 0.0) {
  PointBatch batch;
  batch.timestamp_s = t_s;
  batch.origin_m = origin_m;
  for (int j = kWallMin; j <= kWallMax; ++j) {
    for (int k = kWallMin; k <= kWallMax; ++k) batch.points_m.push_back(centre(wall_x, j, k));
  }
  return batch;
}

// The same batch for the in-process map (points as float, as the server stores them).
inline cenote::PointBatch toMappingBatch(const PointBatch& batch) {
  cenote::PointBatch out;
  out.t_s = batch.timestamp_s;
  out.origin = batch.origin_m;
  for (const auto& p : batch.points_m) out.points.push_back(p.cast<float>());
  out.colors = batch.rgb;
  return out;
}

}  // namespace cenote::client::test
