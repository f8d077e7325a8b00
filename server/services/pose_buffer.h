// pose_buffer.h: camera poses streamed at VIO rate (Ingest.StreamPoses), kept for matching frames
// that arrive without a pose of their own. A frame's pose is interpolated between the two stored
// poses that bracket its timestamp (io/trajectory/trajectory.h: linear + slerp, at most
// max_gap_s apart), exactly as `cenote run` does with a trajectory file, so the same poses give
// the same map.
// Bounded whatever the stream sends: poses older than history_s before the newest are dropped,
// and at most max_poses are kept (the oldest go first). One careless or bad pose cannot lock the
// stream out: a pose more than max_jump_s after the stream's clock (the newest pose, or the newest
// frame's time when it is later) is refused, and a frame's time drops poses stamped more than
// max_jump_s after it (a far-future pose accepted before any frame came is gone at the first frame).
// Units: seconds, metres; poses are T_world_cam of the raw left camera.
// Threads: any number of writers and readers.
#pragma once

#include <chrono>
#include <condition_variable>
#include <deque>
#include <limits>
#include <mutex>
#include <optional>

#include "io/trajectory/tum_trajectory.h"

namespace cenote::server {

struct PoseBufferLimits {
  double history_s = 60.0;    // server.pose_history_s
  size_t max_poses = 100000;  // server.limits.max_poses
  double max_jump_s = 60.0;   // server.pose_max_jump_s
};

class PoseBuffer {
 public:
  explicit PoseBuffer(PoseBufferLimits limits) : limits_(limits) {}

  // @throws StatusError INVALID_ARGUMENT when t_s is not after the newest pose, or more than
  //         max_jump_s after the stream's clock.
  void add(const io::StampedPose& pose);
  // A frame stamped t_s arrived: advances the stream's clock and drops poses stamped more than
  // max_jump_s after it (they cannot belong to this stream's clock).
  void noteFrameTime(double t_s);
  // The pose at t_s; waits until `deadline` for a pose at or after t_s to arrive (VIO runs a
  // little behind the cameras). nullopt: none brackets t_s within max_gap_s.
  std::optional<Eigen::Isometry3d> poseAt(double t_s, double max_gap_s, std::chrono::steady_clock::time_point deadline);
  size_t received() const;
  size_t size() const;

 private:
  const PoseBufferLimits limits_;
  mutable std::mutex mutex_;
  std::condition_variable added_;
  std::deque<io::StampedPose> poses_;
  double newest_frame_t_s_ = -std::numeric_limits<double>::infinity();
  size_t received_ = 0;
};

}  // namespace cenote::server
