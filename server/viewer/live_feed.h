// live_feed.h: what the viewer shows besides the map: the camera's poses (one per integrated
// batch), the latest fused point cloud and the latest camera images, handed over by ingest after
// each integration.
// Bounded: at most max_poses poses (the oldest dropped), one cloud, thinned to max_points (every
// k-th point, so the same batch gives the same cloud), and one pair of images. A pose costs a few
// dozen bytes and is always kept (a late viewer sees the whole trajectory); the cloud is copied
// only while a viewer client wants it (setWanted), the images are made (encoded by the poster,
// host_viewer.h) only while one wants them and at most image_hz times a second (imagesDue), so
// ingest pays nothing for either otherwise.
// Units: metres, world frame, seconds. Threads: post() from any ingest thread; read from any.
#pragma once

#include <Eigen/Geometry>
#include <atomic>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "common/point_batch.h"

namespace cenote::server::viewer {

class LiveFeed {
 public:
  // image_hz: camera images at most this often; 0: never.
  LiveFeed(size_t max_points, size_t max_poses, double image_hz = 0.0)
      : max_points_(max_points), max_poses_(max_poses), image_period_s_(image_hz > 0.0 ? 1.0 / image_hz : -1.0) {}

  // After `batch` was integrated; T_world_cam when the frame's orientation is known (frames),
  // otherwise the camera is placed at batch.origin, unrotated (point batches).
  void post(const PointBatch& batch, const std::optional<Eigen::Isometry3d>& T_world_cam);
  // Whether some viewer client wants the cloud, the camera images (the feed's worker says so each tick).
  void setWanted(bool cloud, bool images) {
    wanted_.store(cloud, std::memory_order_relaxed);
    images_wanted_.store(images, std::memory_order_relaxed);
  }

  struct Poses {
    uint64_t version = 0;                       // counts posts; 0: none yet
    std::vector<Eigen::Isometry3d> trajectory;  // oldest first; the last is the current camera
  };
  Poses poses() const;
  // The current camera and the post it came from; nullopt before the first post.
  std::optional<std::pair<Eigen::Isometry3d, uint64_t>> latest() const;
  // The latest cloud and the post it came from (0: none).
  std::pair<std::shared_ptr<const PointBatch>, uint64_t> cloud() const;
  uint64_t version() const;

  // The latest camera images: the rectified left image and the disparity preview, JPEG files.
  struct Images {
    uint64_t version = 0;  // counts postImages; 0: none yet
    double t_s = 0.0;      // the frame's time
    std::shared_ptr<const std::string> left_jpeg, disparity_jpeg;
  };
  // A viewer wants images, images are on (image_hz > 0) and the last were posted at least
  // 1 / image_hz ago: the poster may make the next pair.
  bool imagesDue() const;
  void postImages(double t_s, std::string left_jpeg, std::string disparity_jpeg);
  Images images() const;

 private:
  const size_t max_points_, max_poses_;
  const double image_period_s_;  // < 0: no images
  std::atomic<bool> wanted_{false}, images_wanted_{false};
  std::atomic<int64_t> next_image_ns_{0};  // steady clock
  mutable std::mutex mutex_;
  uint64_t version_ = 0;
  std::deque<Eigen::Isometry3d> trajectory_;
  std::shared_ptr<const PointBatch> cloud_;
  uint64_t cloud_version_ = 0;
  Images images_;
};

}  // namespace cenote::server::viewer
