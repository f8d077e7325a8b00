#include "server/host/map_host.h"

#include <malloc.h>

#include "common/error.h"
#include "common/locked_copy.h"
#include "server/cpu/cpu_scheduling.h"

namespace cenote::server {
namespace {

// Gives the memory the map has just freed back to the system. The map's blocks are small
// allocations (an 8^3-voxel leaf is 2 KB), made by the writer thread in its malloc arena among
// longer-lived ones; glibc keeps freed chunks for reuse and returns to the kernel only a large
// free top of a heap, so after Admin.Reset the map held 16 MB and cenote-server's RSS stayed at
// 670 MB (issue 14). malloc_trim(0) releases every whole free page of every arena (madvise
// MADV_DONTNEED): one pass over the free chunks, milliseconds, and only after a change that forgot
// voxels. A lower M_TRIM_THRESHOLD would not do: it too trims only the top of a heap.
void returnFreedMemory() {
#ifdef __GLIBC__
  malloc_trim(0);
#endif
}

}  // namespace

MapHost::MapHost(std::unique_ptr<mapping::OccupancyMap> map, const MapHostOptions& options)
    : map_(std::move(map)),
      distance_(std::make_unique<mapping::DistanceField>(*map_)),
      frontiers_(std::make_unique<mapping::FrontierMap>(*map_)),
      feed_(options.max_subscriber_lag, options.max_subscriber_bytes),
      options_(options),
      writer_(options.ingest_nice) {
  // A loaded map: derive everything once before serving (stats() walks the grid: ask once).
  const mapping::MapStats loaded = map_->stats();
  if (options.frame_history) {
    history_ = std::make_unique<mapping::MapHistory>(*map_);
    // What a loaded map holds came from no stored frame: corrections leave those blocks as they are.
    if (loaded.occupied + loaded.free > 0) history_->seal(map_->constAccessor().knownBlocks());
  }
  if (loaded.occupied + loaded.free > 0) {
    distance_->rebuild();
    frontiers_->rebuild();
  }
  derived_thread_ = std::thread([this] { derivedLoop(); });
}

MapHost::~MapHost() {
  // Changes still queued reach the map, the feed and the derived structures while they all
  // exist; then the derived thread stops and subscribers see the feed end.
  writer_.finish();
  {
    std::lock_guard<std::mutex> lock(derived_mutex_);
    stop_ = true;
  }
  derived_cv_.notify_all();
  derived_thread_.join();
  feed_.close();
}

template <typename Change>
mapping::MapDelta MapHost::change(Change&& apply, bool forgets) {
  return writer_.run([&] {
    mapping::MapDelta delta = apply();
    if (forgets && !delta.isEmpty()) returnFreedMemory();
    const uint64_t version = map_->version();
    {
      std::lock_guard<std::mutex> lock(derived_mutex_);
      pending_.merge(delta);
      ++published_changes_;
    }
    derived_cv_.notify_all();
    feed_.publish(MapChange{version, delta});
    return delta;
  });
}

mapping::MapDelta MapHost::integrate(const PointBatch& batch) {
  mapping::MapDelta delta = change([&] { return history_ ? history_->integrate(batch) : map_->integrate(batch); }, false);
  if (live_) live_->post(batch, std::nullopt);
  std::lock_guard<std::mutex> lock(derived_mutex_);
  ++batches_;
  return delta;
}

mapping::MapDelta MapHost::integrateFrame(const PointBatch& batch, const Eigen::Isometry3d& T_world_cam,
                                          const Eigen::Isometry3d& T_pose_cam) {
  mapping::MapDelta delta = change(
      [&] { return history_ ? history_->integrate(batch, T_world_cam, T_pose_cam) : map_->integrate(batch); }, false);
  if (live_) live_->post(batch, T_world_cam);
  std::lock_guard<std::mutex> lock(derived_mutex_);
  ++batches_;
  return delta;
}

mapping::CorrectionSummary MapHost::correctPoses(const std::vector<mapping::CorrectedPose>& poses) {
  if (!history_) {
    throw FailedPreconditionError("correct poses: the server keeps no frame history (server.frame_history is false)");
  }
  // In steps on the writer thread (MapHistory::movesPerStep() moved frames each): frames that
  // arrive meanwhile are integrated between them, and the final replay includes them where they
  // touch the affected blocks. An ingest frame waits for at most one step: with one march a step
  // instead of movesAtOnce(), ingest at 15 Hz during a correction ran at twice the rate
  // (bench/correction_ingest_bench, docs/PERFORMANCE.md).
  std::lock_guard<std::mutex> one_at_a_time(correction_mutex_);
  mapping::CorrectionPlan plan = writer_.run([&] { return history_->planCorrection(poses); });
  const size_t step = history_->movesPerStep();
  for (size_t i = 0; i < plan.moved.size(); i += step) writer_.run([&] { history_->moveFrames(plan, i, i + step); });
  mapping::CorrectionSummary summary;
  change(
      [&] {
        summary = history_->finishCorrection(plan);
        return summary.delta;
      },
      false);
  return summary;
}

// Clears and crops are not replayed from the frame store: the blocks they changed keep their
// state in later corrections.
mapping::MapDelta MapHost::clearBox(const mapping::Aabb& box_m) {
  return change([&] { return sealed(map_->clearBox(box_m)); }, true);
}

mapping::MapDelta MapHost::clearSphere(const Eigen::Vector3d& centre_m, double radius_m) {
  return change([&] { return sealed(map_->clearSphere(centre_m, radius_m)); }, true);
}

mapping::MapDelta MapHost::cropToRadius(const Eigen::Vector3d& centre_m, double radius_m) {
  return change([&] { return sealed(map_->cropToRadius(centre_m, radius_m)); }, true);
}

mapping::MapDelta MapHost::reset() {
  return change(
      [&] {
        mapping::MapDelta delta = map_->reset();
        if (history_) history_->clear();
        return delta;
      },
      true);
}

mapping::MapDelta MapHost::sealed(mapping::MapDelta delta) {
  if (history_) {
    history_->seal(delta.changed_blocks);
    history_->releaseScratch();
  }
  return delta;
}

uint64_t MapHost::batchesIntegrated() const { return lockedCopy(derived_mutex_, batches_); }

uint64_t MapHost::derivedUpdates() const { return lockedCopy(derived_mutex_, derived_updates_); }

uint64_t MapHost::changesSeenWhenDerivedIdled() const { return lockedCopy(derived_mutex_, idle_changes_); }

bool MapHost::waitForDerived(std::chrono::system_clock::time_point deadline) const {
  std::unique_lock<std::mutex> lock(derived_mutex_);
  last_derived_query_ = Clock::now();
  const uint64_t target = published_changes_;
  if (derived_changes_ >= target) return true;
  ++waiting_queries_;
  derived_cv_.notify_all();
  const bool done = derived_cv_.wait_until(lock, deadline, [&] { return derived_changes_ >= target || stop_; });
  --waiting_queries_;
  return done;
}

bool MapHost::followingQueries(Clock::time_point now) const {
  return last_derived_query_ && now - *last_derived_query_ <= std::chrono::duration<double>(options_.derived_follow_s);
}

void MapHost::derivedLoop() {
  setThreadNice(options_.derived_nice);
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options_.derived_period_s));
  Clock::time_point last_update = Clock::now();
  std::unique_lock<std::mutex> lock(derived_mutex_);
  while (true) {
    const auto due = [&] {
      if (stop_) return true;
      if (derived_changes_ >= published_changes_) return false;
      const Clock::time_point now = Clock::now();
      return waiting_queries_ > 0 || (followingQueries(now) && now >= last_update + period);
    };
    // The kind of wait is chosen again at every wake-up: a change that arrives while following
    // must be picked up when its period ends, not at the next change or query.
    while (!due()) {
      if (derived_changes_ < published_changes_ && followingQueries(Clock::now())) {
        derived_cv_.wait_until(lock, last_update + period);
      } else {
        idle_changes_ = published_changes_;
        derived_cv_.wait(lock);
      }
    }
    if (stop_) return;
    last_update = Clock::now();
    mapping::MapDelta delta;
    std::swap(delta, pending_);
    const uint64_t changes = published_changes_;
    lock.unlock();
    // Deltas merged since the last round are applied at once: one wave over their union.
    if (!delta.isEmpty()) {
      distance_->update(delta);
      frontiers_->update(delta);
    }
    lock.lock();
    derived_changes_ = changes;
    ++derived_updates_;
    derived_cv_.notify_all();
  }
}

}  // namespace cenote::server
