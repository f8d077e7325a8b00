// tunnel_dive.h: the simulated dive of the correction benches (correction_bench,
// correction_ingest_bench): a camera flying along a 3 m wide, 2.5 m high tunnel with rocks on its
// walls, at 0.4 m/s and 15 Hz (2.7 cm a frame), yawing slowly from side to side, ray-cast exactly
// with 1 cm depth noise (tests/mapping/support/analytic_scene.h). The odometry drifts over the last
// `moved` frames (growing to drift_m along x and y and drift_deg of yaw), so that a correction
// giving every frame its true pose moves exactly those frames.
// Units: metres, seconds (frame i at i / 15 s), degrees. Threads: pure functions.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "common/point_batch.h"
#include "mapping/history/map_history.h"
#include "tests/mapping/support/analytic_scene.h"

namespace cenote::bench {

struct TunnelDive {
  mapping::test::Scene scene;
  PinholeCamera camera;
  std::vector<Eigen::Isometry3d> truth, drifted;
};

TunnelDive makeTunnelDive(int frames, int moved, int width, int height, double drift_m, double drift_deg);
// The frame the camera saw at its true pose i, posed at T (where the odometry put it).
PointBatch tunnelFrame(const TunnelDive& d, int i, const Eigen::Isometry3d& T);
// The correction that gives every frame its true pose.
std::vector<mapping::CorrectedPose> trueTunnelPoses(const TunnelDive& d);

}  // namespace cenote::bench
