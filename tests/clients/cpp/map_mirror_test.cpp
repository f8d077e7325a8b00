// MapMirror: a client's copy of the map kept from the update stream, fed updates by hand.
#include "clients/cpp/map_mirror.h"

#include <gtest/gtest.h>

namespace cenote::client::test {
namespace {

TEST(MapMirror, AppliesSnapshotsChangesAndResyncs) {
  MapMirror mirror;
  MapUpdate update;
  update.sequence = 3;
  update.snapshot = true;
  update.voxel_size_m = 0.05;
  UpdateBlock block;
  block.index = Eigen::Vector3i(1, -1, 0);
  block.states[64 * 2 + 8 * 3 + 4] = VoxelState::kOccupied;  // voxel (10, -5, 4)
  block.states[0] = VoxelState::kFree;                       // voxel (8, -8, 0)
  update.blocks = {block};
  mirror.apply(update);
  EXPECT_FALSE(mirror.isSynced());
  update.blocks.clear();
  update.snapshot_complete = true;
  mirror.apply(update);
  EXPECT_TRUE(mirror.isSynced());
  EXPECT_EQ(mirror.state(Eigen::Vector3i(10, -5, 4)), VoxelState::kOccupied);
  EXPECT_EQ(mirror.state(Eigen::Vector3i(8, -8, 0)), VoxelState::kFree);
  EXPECT_EQ(mirror.stateAt(Eigen::Vector3d(0.51, -0.24, 0.21)), VoxelState::kOccupied);
  EXPECT_EQ(mirror.occupied(), 1u);
  // A cleared block (all unknown) is dropped.
  MapUpdate change;
  change.sequence = 4;
  UpdateBlock cleared;
  cleared.index = block.index;
  change.blocks = {cleared};
  mirror.apply(change);
  EXPECT_EQ(mirror.numBlocks(), 0u);
  // A resync replaces everything.
  mirror.apply(update);  // re-add nothing: snapshot with no blocks
  MapUpdate resync;
  resync.sequence = 9;
  resync.snapshot = resync.resync = resync.snapshot_complete = true;
  UpdateBlock other;
  other.index = Eigen::Vector3i(0, 0, 0);
  other.states[1] = VoxelState::kFree;
  resync.blocks = {other};
  mirror.apply(resync);
  EXPECT_EQ(mirror.numBlocks(), 1u);
  EXPECT_EQ(mirror.free(), 1u);
  EXPECT_EQ(mirror.sequence(), 9u);
}

}  // namespace
}  // namespace cenote::client::test
