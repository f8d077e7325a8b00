// pose_buffer.h: camera poses streamed at VIO rate (Ingest.StreamPoses), kept for matching frames
// that arrive without a pose of their own. A frame's pose is interpolated between the two stored
// poses that bracket its timestamp (io/trajectory/trajectory.h: linear + slerp, at most
// max_gap_s apart), exactly as `cenote run` does with a trajectory file, so the same poses give
// the same map. Poses older than history_s before the newest are dropped: memory stays bounded.
// Units: seconds, metres; poses are T_world_cam of the raw left camera.
// Threads: any number of writers and readers.
#pragma once

#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <optional>

#include "io/trajectory/tum_trajectory.h"

namespace cenote::server {

class PoseBuffer {
 public:
  explicit PoseBuffer(double history_s) : history_s_(history_s) {}

  // @throws StatusError INVALID_ARGUMENT when t_s is not after the newest pose.
  void add(const io::StampedPose& pose);
  // The pose at t_s; waits until `deadline` for a pose at or after t_s to arrive (VIO runs a
  // little behind the cameras). nullopt: none brackets t_s within max_gap_s.
  std::optional<Eigen::Isometry3d> poseAt(double t_s, double max_gap_s, std::chrono::steady_clock::time_point deadline);
  size_t received() const;

 private:
  const double history_s_;
  mutable std::mutex mutex_;
  std::condition_variable added_;
  std::deque<io::StampedPose> poses_;
  size_t received_ = 0;
};

}  // namespace cenote::server
