// MapHost's pose corrections: the rebuilt blocks reach the change feed and the distance field like
// any change; without a frame history, or after a reset, there is nothing to correct.
#include <gtest/gtest.h>

#include <filesystem>

#include "common/error.h"
#include "server/host/map_host.h"

namespace cenote::server {
namespace {

// A camera at the origin looking along +x (camera z), a 1 m x 1 m wall 1 m ahead: camera points.
Eigen::Isometry3d lookingAlongX() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = Eigen::Vector3d(0, -1, 0);
  T.linear().col(1) = Eigen::Vector3d(0, 0, -1);
  T.linear().col(2) = Eigen::Vector3d(1, 0, 0);
  return T;
}
PointBatch wallSeenFrom(const Eigen::Isometry3d& T_world_cam) {
  PointBatch batch;
  batch.t_s = 5.0;
  batch.origin = T_world_cam.translation();
  for (int i = 0; i <= 20; ++i) {
    for (int j = 0; j <= 20; ++j) {
      const Eigen::Vector3d p_cam(-0.5 + 0.05 * i, -0.5 + 0.05 * j, 1.0);
      batch.points.push_back((T_world_cam * p_cam).cast<float>());
    }
  }
  return batch;
}

std::unique_ptr<MapHost> makeHost(bool frame_history, mapping::CorrectionMove move = mapping::CorrectionMove::kMarch) {
  MapHostOptions options;
  options.frame_history = frame_history;
  options.derived_period_s = 0.0;
  mapping::MapConfig config;
  config.correction_move = move;
  config.num_threads = 1;  // keeps OpenMP (libgomp is not built for ThreadSanitizer) out: `make tsan-test` runs these
  config.history_dir = (std::filesystem::path(::testing::TempDir()) /
                        ("host-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name())))
                           .string();
  return std::make_unique<MapHost>(std::make_unique<mapping::OccupancyMap>(config), options);
}

double distanceAt(MapHost& host, const Eigen::Vector3d& p_m) {
  EXPECT_TRUE(host.waitForDerived(std::chrono::system_clock::now() + std::chrono::seconds(30)));
  return host.distanceField().query({p_m}).front().distance_m;
}

void movedWallReachesTheFeedAndTheDistanceField(mapping::CorrectionMove move) {
  auto host = makeHost(true, move);
  const Eigen::Isometry3d T_true = lookingAlongX();
  Eigen::Isometry3d T_drifted = T_true;
  T_drifted.translation().x() += 0.5;  // the odometry put the camera 0.5 m ahead: the wall at x = 1.5 m
  host->integrateFrame(wallSeenFrom(T_drifted), T_drifted, Eigen::Isometry3d::Identity());
  // Before: the nearest obstacle to (0.9, 0, 0) is the drifted wall, 0.6 m away (its voxels' face).
  EXPECT_NEAR(distanceAt(*host, Eigen::Vector3d(0.9, 0, 0)), 0.6, 0.06);
  const auto subscription = host->feed().subscribe();
  const mapping::CorrectionSummary summary = host->correctPoses({{5.0, T_true}});
  EXPECT_EQ(summary.frames_moved, 1u);
  EXPECT_EQ(summary.frames_replayed, 1u);
  MapChange change;
  ASSERT_EQ(subscription->next(change, std::chrono::milliseconds(10000)), Subscription::Next::kChange);
  EXPECT_EQ(change.delta.changed_blocks, summary.delta.changed_blocks);
  EXPECT_EQ(change.version, host->map().version());
  // The wall is now at x = 1 m: 0.1 m from (0.9, 0, 0); nothing is left at x = 1.5 m.
  EXPECT_NEAR(distanceAt(*host, Eigen::Vector3d(0.9, 0, 0)), 0.1, 0.06);
  auto acc = host->map().constAccessor();
  EXPECT_EQ(acc.state(host->map().toIndex(Eigen::Vector3d(1.51, 0.02, 0.02))), mapping::VoxelState::kUnknown);
  EXPECT_EQ(acc.state(host->map().toIndex(Eigen::Vector3d(1.01, 0.02, 0.02))), mapping::VoxelState::kOccupied);
}

TEST(MapHostCorrections, TheMovedWallReachesTheFeedAndTheDistanceField) {
  movedWallReachesTheFeedAndTheDistanceField(mapping::CorrectionMove::kMarch);
}

// Resampled (its moves taken MapHistory::movesPerStep() a step): a move by whole voxels, the same wall.
TEST(MapHostCorrections, TheResampledWallReachesTheFeedAndTheDistanceField) {
  movedWallReachesTheFeedAndTheDistanceField(mapping::CorrectionMove::kResample);
}

TEST(MapHostCorrections, WithoutFrameHistoryACorrectionIsAFailedPrecondition) {
  auto host = makeHost(false);
  host->integrateFrame(wallSeenFrom(lookingAlongX()), lookingAlongX(), Eigen::Isometry3d::Identity());
  try {
    host->correctPoses({{5.0, Eigen::Isometry3d::Identity()}});
    FAIL() << "no error";
  } catch (const FailedPreconditionError& e) {
    EXPECT_STREQ(e.what(), "correct poses: the server keeps no frame history (server.frame_history is false)");
  }
}

TEST(MapHostCorrections, AfterAResetOrForStreamedPointsNothingMoves) {
  auto host = makeHost(true);
  Eigen::Isometry3d T = lookingAlongX();
  host->integrate(wallSeenFrom(T));  // points without a camera pose: never moved
  T.translation().x() += 0.3;
  EXPECT_EQ(host->correctPoses({{5.0, T}}).frames_moved, 0u);
  host->integrateFrame(wallSeenFrom(lookingAlongX()), lookingAlongX(), Eigen::Isometry3d::Identity());
  host->reset();
  const mapping::CorrectionSummary summary = host->correctPoses({{5.0, T}});
  EXPECT_EQ(summary.frames_moved, 0u);
  EXPECT_TRUE(summary.delta.isEmpty());
}

}  // namespace
}  // namespace cenote::server
