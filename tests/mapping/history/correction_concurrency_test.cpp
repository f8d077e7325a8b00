// Readers during a pose correction (mapping/history/map_history.h), in both of its modes: every
// block they read is either its state before the correction or after it, never a mix; the map ends
// as a twin corrected alone ends, which with the march is the one built from scratch with the
// corrected poses. Part of mapping_concurrency_test, which ThreadSanitizer builds (-DCENOTE_TSAN=ON) run.
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <thread>

#include "mapping/history/map_history.h"
#include "tests/mapping/support/block_snapshot.h"
#include "tests/mapping/support/drifted_frames.h"

namespace cenote::mapping {
namespace {

using test::blockIn;
using test::sameBlock;

void readersSeeEachBlockOldOrNew(CorrectionMove move) {
  MapConfig config;
  config.voxel_size_m = 0.05;
  config.publish_blocks = 4;  // many short exclusive sections: readers interleave often
  config.num_threads = 1;     // keeps OpenMP (not built for ThreadSanitizer) out
  config.correction_move = move;
  const std::string base =
      (std::filesystem::path(::testing::TempDir()) / (std::string("correction-concurrency-") + toString(move))).string();
  config.history_dir = base + "-drifted";
  const PinholeCamera camera{.width = 80, .height = 60, .fx = 60.0, .fy = 60.0, .cx = 39.5, .cy = 29.5};
  const auto frames = test::driftedRoomSweep(12, camera, 0.2, 2.0, config.history_quantum_m);
  OccupancyMap map(config);
  MapHistory history(map);
  MapConfig truth_config = config;
  truth_config.history_dir = base + "-truth";
  OccupancyMap truth(truth_config);
  MapHistory truth_history(truth);
  MapConfig twin_config = config;
  twin_config.history_dir = base + "-twin";
  OccupancyMap twin(twin_config);
  MapHistory twin_history(twin);
  std::vector<CorrectedPose> poses;
  for (const auto& f : frames) {
    history.integrate(f.batchAt(f.T_drifted), f.T_drifted);
    twin_history.integrate(f.batchAt(f.T_drifted), f.T_drifted);
    truth_history.integrate(f.batchAt(f.T_true), f.T_true);
    poses.push_back({f.t_s, f.T_true});
  }
  twin_history.correct(poses);
  const auto before = test::snapshotBlocks(map);
  const auto after = test::snapshotBlocks(twin);
  const auto from_scratch = test::snapshotBlocks(truth);
  std::vector<BlockIndex> blocks;
  for (const auto& [b, view] : before) blocks.emplace_back(b[0], b[1], b[2]);
  for (const auto& [b, view] : after) {
    if (before.count(b) == 0) blocks.emplace_back(b[0], b[1], b[2]);
  }
  std::atomic<bool> done{false};
  std::atomic<size_t> reads{0}, mixed{0}, saw_old{0}, saw_new{0};
  std::vector<std::thread> readers;
  for (int t = 0; t < 2; ++t) {
    readers.emplace_back([&, t] {
      BlockView view;
      while (!done.load()) {
        for (size_t i = t; i < blocks.size(); i += 2) {
          {
            auto acc = map.constAccessor();
            acc.readBlock(blocks[i], view);
          }
          const bool is_old = sameBlock(view, blockIn(before, blocks[i]));
          const bool is_new = sameBlock(view, blockIn(after, blocks[i]));
          mixed += !is_old && !is_new;
          saw_old += is_old && !is_new;
          saw_new += is_new && !is_old;
          ++reads;
        }
      }
    });
  }
  while (reads.load() < blocks.size()) std::this_thread::yield();  // readers are running
  const CorrectionSummary summary = history.correct(poses);
  const size_t reads_then = reads.load();
  while (reads.load() < reads_then + 2 * blocks.size()) std::this_thread::yield();  // and read the new state
  done = true;
  for (auto& r : readers) r.join();
  EXPECT_GT(summary.frames_moved, 0u);
  EXPECT_EQ(mixed.load(), 0u) << "of " << reads.load() << " block reads";
  EXPECT_GT(saw_old.load(), 0u);
  EXPECT_GT(saw_new.load(), 0u);
  const auto final_blocks = test::snapshotBlocks(map);
  for (const BlockIndex& b : blocks) {
    EXPECT_TRUE(sameBlock(blockIn(final_blocks, b), blockIn(after, b))) << "block " << b.transpose();
    if (move == CorrectionMove::kMarch) {
      EXPECT_TRUE(sameBlock(blockIn(final_blocks, b), blockIn(from_scratch, b))) << "block " << b.transpose();
    }
  }
}

TEST(CorrectionConcurrency, ReadersSeeEachBlockOldOrNewNeverAMix) { readersSeeEachBlockOldOrNew(CorrectionMove::kMarch); }

TEST(CorrectionConcurrency, ReadersSeeEachResampledBlockOldOrNewNeverAMix) {
  readersSeeEachBlockOldOrNew(CorrectionMove::kResample);
}

}  // namespace
}  // namespace cenote::mapping
