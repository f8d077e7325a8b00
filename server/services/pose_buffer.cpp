#include "server/services/pose_buffer.h"

#include <algorithm>
#include <cmath>

#include "common/locked_copy.h"
#include "io/trajectory/trajectory.h"
#include "server/wire/status_error.h"

namespace cenote::server {

void PoseBuffer::add(const io::StampedPose& pose) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!poses_.empty() && !(pose.t_s > poses_.back().t_s)) {
      throw invalidArgument("pose at t = " + std::to_string(pose.t_s) + " s is not after the previous pose (t = " +
                            std::to_string(poses_.back().t_s) + " s): timestamps must increase");
    }
    const double clock_s = poses_.empty() ? newest_frame_t_s_ : std::max(poses_.back().t_s, newest_frame_t_s_);
    if (std::isfinite(clock_s) && pose.t_s - clock_s > limits_.max_jump_s) {
      throw invalidArgument("pose at t = " + std::to_string(pose.t_s) + " s is " + std::to_string(pose.t_s - clock_s) +
                            " s after the stream's clock (t = " + std::to_string(clock_s) +
                            " s): more than server.pose_max_jump_s = " + std::to_string(limits_.max_jump_s) +
                            " s; is it stamped with the cameras' clock?");
    }
    poses_.push_back(pose);
    ++received_;
    while (poses_.size() > 2 && poses_.front().t_s < pose.t_s - limits_.history_s) poses_.pop_front();
    while (poses_.size() > limits_.max_poses) poses_.pop_front();
  }
  added_.notify_all();
}

void PoseBuffer::noteFrameTime(double t_s) {
  if (!std::isfinite(t_s)) return;
  std::lock_guard<std::mutex> lock(mutex_);
  newest_frame_t_s_ = std::max(newest_frame_t_s_, t_s);
  while (!poses_.empty() && poses_.back().t_s - newest_frame_t_s_ > limits_.max_jump_s) poses_.pop_back();
}

std::optional<Eigen::Isometry3d> PoseBuffer::poseAt(double t_s, double max_gap_s,
                                                    std::chrono::steady_clock::time_point deadline) {
  std::unique_lock<std::mutex> lock(mutex_);
  added_.wait_until(lock, deadline, [&] { return !poses_.empty() && poses_.back().t_s >= t_s - 1e-6; });
  const auto after = std::lower_bound(poses_.begin(), poses_.end(), t_s,
                                      [](const io::StampedPose& p, double t) { return p.t_s < t; });
  // The two samples around t_s (or the one at it): the trajectory's own rules decide.
  std::vector<io::StampedPose> bracket;
  if (after != poses_.begin()) bracket.push_back(*(after - 1));
  if (after != poses_.end()) bracket.push_back(*after);
  if (after != poses_.end() && after + 1 != poses_.end()) bracket.push_back(*(after + 1));
  lock.unlock();
  if (bracket.empty()) return std::nullopt;
  return io::Trajectory(std::move(bracket), "ingest poses").poseAt(t_s, max_gap_s);
}

size_t PoseBuffer::received() const { return lockedCopy(mutex_, received_); }

size_t PoseBuffer::size() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return poses_.size();
}

}  // namespace cenote::server
