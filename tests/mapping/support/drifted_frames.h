// drifted_frames.h: a camera sweeping a room, seen once with its true poses and once with the poses
// a drifting odometry reported (the same camera-frame points under a drifted pose), for the tests
// and bench of pose corrections (mapping/history/map_history.h).
// Points are rounded to `quantum_m` in the camera frame before they are posed, so that a frame
// store rounding them again (map.history_quantum_m, the same value) keeps them exactly.
// Units: metres, seconds (frame i at t = i * 0.1 s). Threads: plain values and pure functions.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "common/point_batch.h"
#include "tests/mapping/support/analytic_scene.h"

namespace cenote::mapping::test {

struct DriftedFrame {
  double t_s = 0.0;
  Eigen::Isometry3d T_true = Eigen::Isometry3d::Identity();     // T_world_cam
  Eigen::Isometry3d T_drifted = Eigen::Isometry3d::Identity();  // what the odometry reported
  std::vector<Eigen::Vector3f> points_cam;                      // rounded, camera frame
  std::vector<std::array<uint8_t, 3>> colors;
  // The frame's batch at pose T (origin: the camera centre).
  PointBatch batchAt(const Eigen::Isometry3d& T) const;
};

// The room the sweep sees (its true surfaces).
Scene driftedRoom();

// `frames` frames of `camera` moving through a 6 x 4 x 3 m room with two spheres; the drift grows
// linearly from 0 at frame 0 to drift_m (along x and y) and drift_deg (yaw) at the last frame.
std::vector<DriftedFrame> driftedRoomSweep(int frames, const PinholeCamera& camera, double drift_m, double drift_deg,
                                           double quantum_m);

}  // namespace cenote::mapping::test
