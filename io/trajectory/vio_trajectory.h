// vio_trajectory.h: the trajectory files of visual-inertial odometry that are not TUM rows.
// OKVIS and SVIn2 (okvis_ros's csv output) write a CSV of the IMU's state:
//   timestamp, p_WS_W_x, p_WS_W_y, p_WS_W_z, q_WS_x, q_WS_y, q_WS_z, q_WS_w, v_WS_W_x, ..., b_g_x, ..., b_a_z
// timestamp in nanoseconds; T_WS: the pose of the IMU (S) in the world (W), a Hamilton quaternion x y z w,
// so the camera's pose is T_WS * T_SC with the rig's extrinsics T_SC (a dataset's T_body_cam). The
// columns are found by the header's names (any order, extra columns ignored); without a header, that
// order. OpenVINS and ORB-SLAM3 write TUM rows (tum_trajectory.h): OpenVINS's are of the IMU, in
// seconds; ORB-SLAM3's in seconds (SaveTrajectoryTUM: the camera) or nanoseconds (SaveTrajectoryEuRoC:
// the IMU in its inertial modes, the camera otherwise).
// Threads: free function; the result is an immutable Trajectory.
#pragma once

#include <string>

#include "io/trajectory/trajectory.h"

namespace cenote::io {

/// Reads an OKVIS / SVIn2 CSV. Poses are T_world_imu.
/// @throws cenote::Error naming the file: a header without one of the columns (named), a line with
///         too few numbers or a quaternion not of unit norm (file and line named), timestamps that do
///         not increase.
Trajectory readOkvisCsv(const std::string& path);

}  // namespace cenote::io
