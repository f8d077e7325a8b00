#include "server/viewer/live_feed.h"

#include <chrono>

#include "common/locked_copy.h"

namespace cenote::server::viewer {
namespace {

int64_t steadyNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

void LiveFeed::post(const PointBatch& batch, const std::optional<Eigen::Isometry3d>& T_world_cam) {
  Eigen::Isometry3d camera = Eigen::Isometry3d::Identity();
  if (T_world_cam) {
    camera = *T_world_cam;
  } else {
    camera.translation() = batch.origin;
  }
  std::shared_ptr<PointBatch> cloud;
  if (wanted_.load(std::memory_order_relaxed) && max_points_ > 0 && !batch.empty()) {
    // Thinned outside the lock: ingest threads never wait for each other here.
    cloud = std::make_shared<PointBatch>();
    const size_t step = (batch.size() + max_points_ - 1) / max_points_;
    cloud->t_s = batch.t_s;
    cloud->origin = batch.origin;
    cloud->points.reserve(batch.size() / step + 1);
    for (size_t i = 0; i < batch.size(); i += step) {
      cloud->points.push_back(batch.points[i]);
      if (batch.hasColor()) cloud->colors.push_back(batch.colors[i]);
    }
  }
  std::lock_guard<std::mutex> lock(mutex_);
  ++version_;
  trajectory_.push_back(camera);
  while (trajectory_.size() > max_poses_) trajectory_.pop_front();
  if (cloud) {
    cloud_ = std::move(cloud);
    cloud_version_ = version_;
  }
}

LiveFeed::Poses LiveFeed::poses() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return {version_, std::vector<Eigen::Isometry3d>(trajectory_.begin(), trajectory_.end())};
}

std::pair<std::shared_ptr<const PointBatch>, uint64_t> LiveFeed::cloud() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return {cloud_, cloud_version_};
}

std::optional<std::pair<Eigen::Isometry3d, uint64_t>> LiveFeed::latest() const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (trajectory_.empty()) return std::nullopt;
  return std::make_pair(trajectory_.back(), version_);
}

uint64_t LiveFeed::version() const { return lockedCopy(mutex_, version_); }

bool LiveFeed::imagesDue() const {
  return image_period_s_ > 0.0 && images_wanted_.load(std::memory_order_relaxed) &&
         steadyNowNs() >= next_image_ns_.load(std::memory_order_relaxed);
}

void LiveFeed::postImages(double t_s, std::string left_jpeg, std::string disparity_jpeg) {
  next_image_ns_.store(steadyNowNs() + static_cast<int64_t>(image_period_s_ * 1e9), std::memory_order_relaxed);
  auto left = std::make_shared<const std::string>(std::move(left_jpeg));
  auto disparity = std::make_shared<const std::string>(std::move(disparity_jpeg));
  std::lock_guard<std::mutex> lock(mutex_);
  images_ = {images_.version + 1, t_s, std::move(left), std::move(disparity)};
}

LiveFeed::Images LiveFeed::images() const { return lockedCopy(mutex_, images_); }

}  // namespace cenote::server::viewer
