// trajectory.h: a timed sequence of poses read from TUM, EuRoC or KITTI files, and the pose at an
// image's timestamp by interpolation (linear in translation, slerp in rotation).
//
// A pose is T_world_x: p_world = T_world_x * p_x, where x is whatever the file describes: the
// camera for TUM and KITTI (KITTI: camera 0), the body (IMU) for EuRoC ground truth. Compose with
// the dataset's extrinsics (transformedBy) to get the camera's trajectory.
//
// Interpolation never guesses: a pose exists at t only between two samples that bracket t and are
// at most `max_gap_s` apart, within 1 microsecond (or at a sample's own timestamp, within 1 microsecond).
// Threads: immutable after construction; share freely.
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "io/trajectory/tum_trajectory.h"

namespace cenote::io {

// kOkvis: the CSV of OKVIS and SVIn2 (io/trajectory/vio_trajectory.h); kOpenVins: TUM rows of the IMU.
enum class TrajectoryFormat { kTum, kEuroc, kKitti, kOkvis, kOpenVins };

class Trajectory {
 public:
  Trajectory() = default;
  // @throws cenote::Error naming `name` when timestamps do not increase strictly or a pose is
  //         non-finite or not a rotation.
  Trajectory(std::vector<StampedPose> poses, std::string name);

  // TUM: `t tx ty tz qx qy qz qw` (seconds, or nanoseconds: tum_trajectory.h). EuRoC: CSV
  // `t_ns, px, py, pz, qw, qx, qy, qz[, ...]`. OKVIS / SVIn2: vio_trajectory.h. OpenVINS: TUM rows.
  // KITTI: 12 numbers per line (row-major 3x4 [R | t]); timestamps from `kitti_times` (one per
  // line, seconds) or, when empty, the line index at 10 Hz.
  // @throws cenote::Error naming the file and line of the first malformed entry.
  static Trajectory read(const std::string& path, TrajectoryFormat format, const std::string& kitti_times = "");

  // The pose at t_s, interpolated between the samples bracketing it when they are at most
  // max_gap_s apart; nullopt otherwise (before the first or after the last sample, in a gap).
  std::optional<Eigen::Isometry3d> poseAt(double t_s, double max_gap_s) const;

  // T_world_y = T_world_x * T_x_y for every pose: e.g. body poses into camera poses.
  Trajectory transformedBy(const Eigen::Isometry3d& T_x_y) const;

  const std::vector<StampedPose>& poses() const { return poses_; }
  size_t size() const { return poses_.size(); }
  bool empty() const { return poses_.empty(); }
  const std::string& name() const { return name_; }

 private:
  std::vector<StampedPose> poses_;
  std::string name_;
};

const char* toString(TrajectoryFormat format);
// "tum", "euroc", "kitti", "okvis" or "openvins". @throws cenote::Error otherwise.
TrajectoryFormat parseTrajectoryFormat(const std::string& name);
// True for the formats whose poses are of the body (IMU): EuRoC, OKVIS, OpenVINS.
bool describesBody(TrajectoryFormat format);
// From the file's content: a header naming p_WS_W_x -> OKVIS, other commas -> EuRoC, 8 numbers -> TUM
// (an OpenVINS file reads as TUM: name it to have its poses taken as the IMU's), 12 -> KITTI.
// @throws cenote::Error when the file is missing or the first data line fits none.
TrajectoryFormat detectTrajectoryFormat(const std::string& path);

}  // namespace cenote::io
