// live_feed.h: what the viewer shows besides the map: the camera's poses (one per integrated
// batch) and the latest fused point cloud, handed over by ingest after each integration.
// Bounded: at most max_poses poses (the oldest dropped) and one cloud, thinned to max_points
// (every k-th point, so the same batch gives the same cloud). A pose costs a few dozen bytes and
// is always kept (a late viewer sees the whole trajectory); the cloud is copied only while a
// viewer client is connected (setWanted), so ingest pays nothing for it otherwise.
// Units: metres, world frame, seconds. Threads: post() from any ingest thread; read from any.
#pragma once

#include <Eigen/Geometry>
#include <atomic>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "common/point_batch.h"

namespace cenote::server::viewer {

class LiveFeed {
 public:
  LiveFeed(size_t max_points, size_t max_poses) : max_points_(max_points), max_poses_(max_poses) {}

  // After `batch` was integrated; T_world_cam when the frame's orientation is known (frames),
  // otherwise the camera is placed at batch.origin, unrotated (point batches).
  void post(const PointBatch& batch, const std::optional<Eigen::Isometry3d>& T_world_cam);
  void setWanted(bool wanted) { wanted_.store(wanted, std::memory_order_relaxed); }

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

 private:
  const size_t max_points_, max_poses_;
  std::atomic<bool> wanted_{false};
  mutable std::mutex mutex_;
  uint64_t version_ = 0;
  std::deque<Eigen::Isometry3d> trajectory_;
  std::shared_ptr<const PointBatch> cloud_;
  uint64_t cloud_version_ = 0;
};

}  // namespace cenote::server::viewer
