// tum_trajectory.h: camera trajectories in the TUM RGB-D text format, and pose lookup by time.
// A line is `t tx ty tz qx qy qz qw` (seconds, metres, unit quaternion of the rotation), giving
// T_world_cam: p_world = R(q) p_cam + t. Lines starting with '#' and blank lines are skipped.
// Timestamps are seconds, or nanoseconds when the first is 1e11 or more (ORB-SLAM3 writes both).
// Timestamps must increase strictly. Lookup takes the nearest pose within a tolerance (no
// interpolation; other formats and interpolation belong to a later component).
// Threads: a TumTrajectory is immutable after reading; share it freely.
#pragma once

#include <Eigen/Geometry>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace cenote::io {

struct StampedPose {
  double t_s = 0.0;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
};

// Largest accepted | |q| - 1 | of a quaternion in the file (files print 6-9 digits; a larger
// deviation means a broken writer, not rounding). The quaternion is normalised after the check.
inline constexpr double kQuaternionNormTolerance = 1e-3;

class TumTrajectory {
 public:
  // @throws cenote::Error naming the file and line for a missing file, a line without exactly 8
  //         numbers, a non-finite value, a quaternion whose norm is not 1 (within
  //         kQuaternionNormTolerance), or a timestamp not after the previous one.
  static TumTrajectory read(const std::string& path);
  // Same, from a stream; `name` stands for the file in messages.
  static TumTrajectory parse(std::istream& in, const std::string& name);

  // The pose whose timestamp is nearest to t_s, when it is within tolerance_s; nullopt otherwise
  // (and for an empty trajectory). On an exact tie, the earlier pose.
  std::optional<StampedPose> lookup(double t_s, double tolerance_s) const;

  const std::vector<StampedPose>& poses() const { return poses_; }
  bool empty() const { return poses_.empty(); }
  size_t size() const { return poses_.size(); }

 private:
  std::vector<StampedPose> poses_;
};

}  // namespace cenote::io
