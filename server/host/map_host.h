// map_host.h: the map the server serves, the structures derived from it (distance field,
// frontiers) and the feed of its changes. Every change of the map goes through here, so the
// derived structures and the subscribers see every MapDelta, in order.
//
// Changes run one at a time on the map's writer thread (serial_worker.h), at a lower CPU priority
// than the gRPC handlers: when the cores are busy, planners' short queries go first.
// The distance field and the frontiers are brought up to date by a thread of their own, lower
// still, from the accumulated deltas: at once when a distance or frontier query is waiting, and
// every `derived_period_s` while the map changes, as long as such a query came within the last
// `derived_follow_s` (a planner asking every few seconds then finds them nearly current). Ingest
// never waits for them, and a map nobody asks distances of spends no CPU on them: keeping them
// current took a third of the server's CPU while ingesting 70k-point frames at 15 Hz (perf,
// bench/server_bench). A distance or frontier query first waits (up to its deadline) until they
// include every change made before it arrived: a client reads its own writes.
// Units: metres, world frame, seconds.
// Threads: changes from any thread (they queue for the writer thread); queries from any number of
// threads (the map's own reader locks; see mapping/occupancy_map.h).
#pragma once

#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "common/point_batch.h"
#include "mapping/distance/distance_field.h"
#include "mapping/frontier/frontier_map.h"
#include "mapping/history/map_history.h"
#include "mapping/occupancy_map.h"
#include "server/host/change_feed.h"
#include "server/host/map_host_options.h"
#include "server/host/serial_worker.h"
#include "server/viewer/live_feed.h"

namespace cenote::server {

class MapHost {
 public:
  MapHost(std::unique_ptr<mapping::OccupancyMap> map, const MapHostOptions& options);
  ~MapHost();
  MapHost(const MapHost&) = delete;
  MapHost& operator=(const MapHost&) = delete;

  const mapping::OccupancyMap& map() const { return *map_; }
  ChangeFeed& feed() { return feed_; }

  // @throws cenote::Error for a bad batch (the map is then unchanged).
  mapping::MapDelta integrate(const PointBatch& batch);
  // A fused frame of the server's pipeline, seen by the camera T_world_cam (the rectified left
  // camera); T_pose_cam: that camera in the frame CorrectPoses gives poses of (the raw left camera).
  // With options.frame_history it is kept for corrections; otherwise integrate(batch).
  mapping::MapDelta integrateFrame(const PointBatch& batch, const Eigen::Isometry3d& T_world_cam,
                                   const Eigen::Isometry3d& T_pose_cam);
  // Integrated batches are handed on to `live` (the viewer's camera and cloud); null: none. Call
  // before serving.
  void setLiveFeed(viewer::LiveFeed* live) { live_ = live; }
  viewer::LiveFeed* liveFeed() const { return live_; }
  // Applies corrected poses of past frames (mapping/history/map_history.h) on the writer thread, in
  // steps of one moved frame's ray march each, between which other changes (ingest) run; then the
  // blocks are rebuilt and swapped in one change, which goes to the feed and the derived
  // structures like any other. One correction at a time (a second waits).
  // @throws FailedPreconditionError without a frame history; Error for bad poses (nothing changes).
  mapping::CorrectionSummary correctPoses(const std::vector<mapping::CorrectedPose>& poses);
  mapping::MapDelta clearBox(const mapping::Aabb& box_m);
  mapping::MapDelta clearSphere(const Eigen::Vector3d& centre_m, double radius_m);
  mapping::MapDelta cropToRadius(const Eigen::Vector3d& centre_m, double radius_m);
  // Clear, crop and reset give the memory the map frees back to the system (malloc_trim).
  mapping::MapDelta reset();
  uint64_t batchesIntegrated() const;

  // Waits until the distance field and frontiers include every change made so far.
  // @return false when `deadline` came first.
  bool waitForDerived(std::chrono::system_clock::time_point deadline) const;
  const mapping::DistanceField& distanceField() const { return *distance_; }
  // Rounds of distance field and frontier updates done so far (each covers all changes pending).
  uint64_t derivedUpdates() const;
  const mapping::FrontierMap& frontiers() const { return *frontiers_; }
  // For tests, which cannot otherwise see a decision not to update: the number of changes made
  // when the derived thread last went to sleep with no time limit (until the next change, query or
  // the end), i.e. decided that those not yet derived wait for a query. 0 until it first does.
  uint64_t changesSeenWhenDerivedIdled() const;

 private:
  // Runs `apply` on the writer thread and hands its delta on; forgets: it may free map memory
  // (clear, crop, reset), which is then given back to the system.
  template <typename Change>
  mapping::MapDelta change(Change&& apply, bool forgets);
  void derivedLoop();
  // Marks the blocks a clear or crop changed as not to be rebuilt by corrections.
  mapping::MapDelta sealed(mapping::MapDelta delta);

  std::unique_ptr<mapping::OccupancyMap> map_;
  std::unique_ptr<mapping::MapHistory> history_;  // with options.frame_history; used on the writer thread
  std::mutex correction_mutex_;                   // one correction's steps at a time
  std::unique_ptr<mapping::DistanceField> distance_;
  std::unique_ptr<mapping::FrontierMap> frontiers_;
  ChangeFeed feed_;

  const MapHostOptions options_;
  mutable std::mutex derived_mutex_;
  mutable std::condition_variable derived_cv_;
  mapping::MapDelta pending_;       // changes not yet in the derived structures
  uint64_t published_changes_ = 0;  // changes made
  uint64_t derived_changes_ = 0;    // changes the derived structures include
  uint64_t derived_updates_ = 0;    // rounds of derived updates
  uint64_t idle_changes_ = 0;       // published_changes_ at the derived thread's last untimed wait
  uint64_t batches_ = 0;
  viewer::LiveFeed* live_ = nullptr;
  using Clock = std::chrono::steady_clock;
  bool followingQueries(Clock::time_point now) const;

  mutable int waiting_queries_ = 0;  // distance / frontier queries waiting for the derived structures
  mutable std::optional<Clock::time_point> last_derived_query_;  // the latest such query's arrival
  bool stop_ = false;
  std::thread derived_thread_;
  SerialWorker writer_;  // ~MapHost finishes its queued changes first
};

}  // namespace cenote::server
