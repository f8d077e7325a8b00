// MapHost during a pose correction: ingest goes on (its frames integrated between the correction's
// steps), block reads and distance queries are answered, every block a reader sees is its state
// before the correction or after it, never a mix, and the map ends as the one built from scratch.
// Part of server_concurrency_test, which ThreadSanitizer builds (-DCENOTE_TSAN=ON, `make tsan-test`)
// run.
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <set>
#include <thread>

#include "server/host/map_host.h"
#include "tests/mapping/support/block_snapshot.h"
#include "tests/mapping/support/drifted_frames.h"

namespace cenote::server {
namespace {

using Blocks = mapping::test::BlockSnapshot;
using mapping::test::blockIn;
using mapping::test::sameBlock;
using mapping::test::snapshotBlocks;

// Frame i of the ingest that goes on during the correction: a wall 1 m ahead of a camera 20 m
// from the room (so it shares no block with it), at t = 10 + 0.1 i s, after every corrected pose.
PointBatch farWall(int i, Eigen::Isometry3d& T_world_cam) {
  T_world_cam = Eigen::Isometry3d::Identity();
  T_world_cam.translation() = Eigen::Vector3d(20.0 + 0.05 * i, 0.0, 0.0);
  PointBatch batch;
  batch.t_s = 10.0 + 0.1 * i;
  batch.origin = T_world_cam.translation();
  for (int u = 0; u <= 20; ++u) {
    for (int v = 0; v <= 20; ++v)
      batch.points.push_back((T_world_cam * Eigen::Vector3d(-0.5 + 0.05 * u, -0.5 + 0.05 * v, 1.0)).cast<float>());
  }
  return batch;
}

mapping::MapConfig configIn(const std::string& dir) {
  mapping::MapConfig config;
  config.voxel_size_m = 0.05;
  config.publish_blocks = 4;                                 // many short exclusive sections: readers interleave often
  config.num_threads = 1;                                    // keeps OpenMP (not built for ThreadSanitizer) out
  config.correction_move = mapping::CorrectionMove::kMarch;  // the map from scratch, bit for bit
  config.history_dir = (std::filesystem::path(::testing::TempDir()) / dir).string();
  return config;
}

TEST(MapHostCorrectionConcurrency, IngestAndReadersGoOnAndSeeEachBlockOldOrNew) {
  constexpr int kRoomFrames = 12, kFarFrames = 8;
  const PinholeCamera camera{.width = 80, .height = 60, .fx = 60.0, .fy = 60.0, .cx = 39.5, .cy = 29.5};
  const mapping::MapConfig config = configIn("host-correction-concurrency");
  const auto frames = mapping::test::driftedRoomSweep(kRoomFrames, camera, 0.2, 2.0, config.history_quantum_m);
  MapHostOptions options;
  options.frame_history = true;
  options.derived_period_s = 0.0;  // the distance field follows every change
  MapHost host(std::make_unique<mapping::OccupancyMap>(config), options);
  // The truth: every frame from scratch, the room's with their true poses.
  mapping::OccupancyMap truth(configIn("host-correction-concurrency-truth"));
  mapping::MapHistory truth_history(truth);
  std::vector<mapping::CorrectedPose> poses;
  for (const auto& f : frames) {
    host.integrateFrame(f.batchAt(f.T_drifted), f.T_drifted, Eigen::Isometry3d::Identity());
    truth_history.integrate(f.batchAt(f.T_true), f.T_true);
    poses.push_back({f.t_s, f.T_true});
  }
  const Blocks before = snapshotBlocks(host.map());
  const Blocks after = snapshotBlocks(truth);
  std::vector<mapping::BlockIndex> room_blocks;
  for (const auto& [b, view] : before) room_blocks.emplace_back(b[0], b[1], b[2]);
  for (const auto& [b, view] : after) {
    if (before.count(b) == 0) room_blocks.emplace_back(b[0], b[1], b[2]);
  }
  const auto subscription = host.feed().subscribe();

  std::atomic<bool> done{false};
  std::atomic<size_t> reads{0}, mixed{0}, saw_old{0}, saw_new{0}, distance_queries{0};
  std::thread block_reader([&] {
    mapping::BlockView view;
    while (!done.load()) {
      for (const mapping::BlockIndex& b : room_blocks) {
        {
          auto acc = host.map().constAccessor();
          acc.readBlock(b, view);
        }
        const bool is_old = sameBlock(view, blockIn(before, b));
        const bool is_new = sameBlock(view, blockIn(after, b));
        mixed += !is_old && !is_new;
        saw_old += is_old && !is_new;
        saw_new += is_new && !is_old;
        ++reads;
      }
    }
  });
  std::thread distance_reader([&] {
    while (!done.load()) {
      host.distanceField().query({Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(20.0, 0.0, 0.5)});
      ++distance_queries;
    }
  });
  while (reads.load() < room_blocks.size()) std::this_thread::yield();  // the readers are running
  while (distance_queries.load() == 0) std::this_thread::yield();
  std::thread ingest([&] {
    for (int i = 0; i < kFarFrames; ++i) {
      Eigen::Isometry3d T_world_cam;
      host.integrateFrame(farWall(i, T_world_cam), T_world_cam, Eigen::Isometry3d::Identity());
    }
  });
  const mapping::CorrectionSummary summary = host.correctPoses(poses);
  ingest.join();
  const size_t reads_then = reads.load();
  while (reads.load() < reads_then + 2 * room_blocks.size()) std::this_thread::yield();  // and read the new state
  done = true;
  block_reader.join();
  distance_reader.join();
  for (int i = 0; i < kFarFrames; ++i) {
    Eigen::Isometry3d T_world_cam;
    truth_history.integrate(farWall(i, T_world_cam), T_world_cam);
  }

  EXPECT_EQ(summary.frames_moved, static_cast<size_t>(kRoomFrames - 1));  // frame 0 has no drift
  EXPECT_EQ(mixed.load(), 0u) << "of " << reads.load() << " block reads";
  EXPECT_GT(saw_old.load(), 0u);
  EXPECT_GT(saw_new.load(), 0u);
  EXPECT_GT(distance_queries.load(), 0u);
  EXPECT_EQ(host.batchesIntegrated(), static_cast<uint64_t>(kRoomFrames + kFarFrames));
  // The map is the one built from scratch, room and far wall, block for block.
  const Blocks final_blocks = snapshotBlocks(host.map());
  const Blocks truth_blocks = snapshotBlocks(truth);
  EXPECT_EQ(final_blocks.size(), truth_blocks.size());
  for (const auto& [b, view] : truth_blocks) {
    const mapping::BlockIndex block(b[0], b[1], b[2]);
    EXPECT_TRUE(sameBlock(blockIn(final_blocks, block), view)) << "block " << block.transpose();
  }
  // The feed reported every block the correction changed.
  std::set<std::array<int, 3>> fed;
  MapChange change;
  while (subscription->next(change, std::chrono::milliseconds(0)) == Subscription::Next::kChange) {
    for (const mapping::BlockIndex& b : change.delta.changed_blocks) fed.insert({b.x(), b.y(), b.z()});
  }
  for (const mapping::BlockIndex& b : summary.delta.changed_blocks) {
    EXPECT_EQ(fed.count({b.x(), b.y(), b.z()}), 1u) << "block " << b.transpose() << " changed but was not fed";
  }
  EXPECT_FALSE(summary.delta.isEmpty());
}

}  // namespace
}  // namespace cenote::server
