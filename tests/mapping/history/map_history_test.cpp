// Pose corrections (mapping/history/map_history.h): the corrected map against the map built from
// scratch with the corrected poses, block by block; the frame store's codec, budget and errors.
#include "mapping/history/map_history.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <cmath>
#include <map>
#include <random>

#include "common/error.h"
#include "mapping/detail/block_table.h"
#include "mapping/history/frame_codec.h"
#include "tests/mapping/support/drifted_frames.h"
#include "tests/mapping/support/known_blocks.h"
#include "tests/mapping/support/map_agreement.h"

namespace cenote::mapping {
namespace {

// March by default: most tests here check the map built from scratch, bit for bit.
MapConfig historyConfig(CorrectionMove move = CorrectionMove::kMarch) {
  MapConfig config;
  config.voxel_size_m = 0.05;
  config.num_threads = 2;
  config.correction_move = move;
  // A folder per test (ctest runs tests in parallel).
  config.history_dir = (std::filesystem::path(::testing::TempDir()) /
                        ("frames-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name())))
                           .string();
  return config;
}

PinholeCamera smallCamera() { return {.width = 96, .height = 72, .fx = 70.0, .fy = 70.0, .cx = 47.5, .cy = 35.5}; }

// The map under test with its history, and a reference map with a frame store of its own to compare
// it with block by block.
struct MapAndReference {
  explicit MapAndReference(const MapConfig& config) : map(config), reference(referenceConfig(config)) {}
  static MapConfig referenceConfig(MapConfig config) {
    config.history_dir += "-reference";
    return config;
  }
  OccupancyMap map;
  MapHistory history{map};
  OccupancyMap reference;
  MapHistory reference_history{reference};
};

std::vector<CorrectedPose> truePoses(const std::vector<test::DriftedFrame>& frames) {
  std::vector<CorrectedPose> poses;
  for (const auto& f : frames) poses.push_back({f.t_s, f.T_true});
  return poses;
}

// Blocks of either map whose known voxels, log-odds or colours differ; voxels whose state differs,
// and voxels known in either.
struct MapDifference {
  size_t blocks = 0;
  size_t voxels_differing = 0;
  size_t voxels_known = 0;
  double agreement() const { return voxels_known == 0 ? 1.0 : 1.0 - double(voxels_differing) / voxels_known; }
};
MapDifference compare(const OccupancyMap& a, const OccupancyMap& b) {
  auto acc_a = a.constAccessor();
  auto acc_b = b.constAccessor();
  const std::vector<BlockIndex> blocks = test::blocksKnownInEither(acc_a, acc_b);
  MapDifference d;
  for (const BlockIndex& block : blocks) {
    BlockView va, vb;
    acc_a.readBlock(block, va);
    acc_b.readBlock(block, vb);
    bool same = va.known == vb.known;
    for (int i = 0; i < kBlockVoxels; ++i) {
      const bool ka = (va.known[i >> 6] >> (i & 63)) & 1, kb = (vb.known[i >> 6] >> (i & 63)) & 1;
      if (!ka && !kb) continue;
      ++d.voxels_known;
      const VoxelState sa = !ka ? VoxelState::kUnknown
                                : (a.model().isOccupied(va.log_odds[i]) ? VoxelState::kOccupied : VoxelState::kFree);
      const VoxelState sb = !kb ? VoxelState::kUnknown
                                : (b.model().isOccupied(vb.log_odds[i]) ? VoxelState::kOccupied : VoxelState::kFree);
      d.voxels_differing += sa != sb;
      same &= ka == kb && va.log_odds[i] == vb.log_odds[i];
    }
    const auto ca = acc_a.blockColors(block), cb = acc_b.blockColors(block);
    same &= ca.size() == cb.size();
    for (size_t i = 0; same && i < ca.size(); ++i) {
      same &= ca[i].offset == cb[i].offset && ca[i].rgb == cb[i].rgb && ca[i].count == cb[i].count;
    }
    d.blocks += !same;
  }
  return d;
}

TEST(FrameCodec, PointsAndUpdatesDecodeToWhatWasEncoded) {
  history::FramePoints points;
  points.quantised = {{0, 0, 0}, {-5, 1200, 70000}, {-5, 1201, -2000000000}, {2000000000, -1, 3}};
  points.colors = {{1, 2, 3}, {255, 0, 7}, {9, 9, 9}, {0, 0, 0}};
  const history::FramePoints back = history::decodePoints(history::encodePoints(points, 1), "test");
  EXPECT_EQ(back.quantised, points.quantised);
  EXPECT_EQ(back.colors, points.colors);

  // Three blocks, each hit voxel's colour in one of them (as a ray march makes them).
  const VoxelIndex coloured(-3, 4, 5), other(100, -4, 5);
  const uint64_t its_block = detail::packIndex(blockOf(coloured)), other_block = detail::packIndex(blockOf(other));
  history::FrameUpdates updates;
  updates.keys = {5, its_block, other_block};
  ASSERT_LT(its_block, other_block);
  updates.masks.resize(3);
  updates.masks[0].free[3] = 0xdeadbeefull;
  updates.masks[1].hit[7] = ~0ull;
  updates.masks[2].free[1] = 7;
  updates.colors = {{coloured, {10, 20, 30}}, {other, {1, 2, 3}}};
  const history::FrameUpdates u = history::decodeUpdates(history::encodeUpdates(updates, 1), "test");
  EXPECT_EQ(u.keys, updates.keys);
  ASSERT_EQ(u.masks.size(), 3u);
  EXPECT_EQ(u.masks[0].free, updates.masks[0].free);
  EXPECT_EQ(u.masks[1].hit, updates.masks[1].hit);
  EXPECT_EQ(u.masks[2].free, updates.masks[2].free);
  ASSERT_EQ(u.colors.size(), 2u);
  EXPECT_EQ(u.colors[1].ijk, other);
  EXPECT_EQ(u.colors[1].rgb, (std::array<uint8_t, 3>{1, 2, 3}));

  // Only the blocks asked for keep their masks and colours, each with its index in `keep`; the
  // others' keys are listed. A key asked for that the frame never touched is no error.
  const std::vector<uint64_t> keep = {4, 5, its_block};
  const history::FrameUpdates some = history::decodeUpdates(history::encodeUpdates(updates, 1), "test", keep);
  EXPECT_EQ(some.keys, (std::vector<uint64_t>{5, its_block}));
  EXPECT_EQ(some.kept_at, (std::vector<uint32_t>{1, 2}));
  EXPECT_EQ(some.others, (std::vector<uint64_t>{other_block}));
  ASSERT_EQ(some.masks.size(), 2u);
  EXPECT_EQ(some.masks[0].free, updates.masks[0].free);
  EXPECT_EQ(some.masks[1].hit, updates.masks[1].hit);
  ASSERT_EQ(some.colors.size(), 1u);
  EXPECT_EQ(some.colors[0].ijk, coloured);
  // An empty `keep`: the keys alone.
  const history::FrameUpdates keys = history::decodeUpdates(history::encodeUpdates(updates, 1), "test", {});
  EXPECT_TRUE(keys.keys.empty() && keys.masks.empty() && keys.colors.empty());
  EXPECT_EQ(keys.others, updates.keys);
}

TEST(FrameCodec, QuantisedCoordinateRoundsAsLlroundDoes) {
  // Halves (away from zero), their neighbours on either side, the classic floor(x + 0.5) trap
  // (0.49999999999999994), the ends of an int, and random quotients.
  std::vector<double> xs = {
      0.0,       -0.0,       0.5,          -0.5,         1.5, -1.5, 2.5, -2.5, 0.49999999999999994, -0.49999999999999994,
      1e6 + 0.5, -1e6 - 0.5, 2147483646.5, -2147483647.5};
  for (double half : {0.5, 1.5, 12345.5, -7.5}) {
    xs.push_back(std::nextafter(half, 0.0));
    xs.push_back(std::nextafter(half, 1e9));
    xs.push_back(std::nextafter(half, -1e9));
  }
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> metres(-50.0, 50.0);
  for (int i = 0; i < 100000; ++i) xs.push_back(metres(rng) / 0.001);
  for (double x : xs) {  // quantum 1: the quotient is x itself
    EXPECT_EQ(history::quantisedCoordinate(x, 1.0), static_cast<int>(std::llround(x))) << "x = " << x;
  }
  for (int i = 0; i < 100000; ++i) {
    const double p = metres(rng);
    EXPECT_EQ(history::quantisedCoordinate(p, 0.001), static_cast<int>(std::llround(p / 0.001))) << "p = " << p;
  }
}

TEST(FrameCodec, DamagedBytesAreAnIoErrorNamingTheFrame) {
  std::string bytes = history::encodeUpdates(history::FrameUpdates{}, 1);
  bytes.resize(bytes.size() - 1);
  try {
    history::decodeUpdates(bytes, "frame 7");
    FAIL() << "no error";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("frame store: frame 7 does not decode"), std::string::npos) << e.what();
  }
}

TEST(FrameStore, PutUpdatesRewritesTheUpdatesAloneAndKeepsTheBytesCounted) {
  history::FrameStore store(historyConfig().history_dir, 1 << 20);
  history::FrameMeta meta;
  meta.t_s = 1.5;
  store.put(3, meta, "points", "old updates");
  EXPECT_EQ(store.bytes(), 6u + 11u);
  meta.T_world_cam.translation() = Eigen::Vector3d(1.0, 2.0, 3.0);
  store.putUpdates(3, meta, "new");
  EXPECT_EQ(store.readPoints(3), "points");
  EXPECT_EQ(store.readUpdates(3), "new");
  EXPECT_EQ(store.meta(3).T_world_cam.translation(), Eigen::Vector3d(1.0, 2.0, 3.0));
  EXPECT_EQ(store.bytes(), 6u + 3u);
  size_t on_disk = 0;
  for (const auto& e : std::filesystem::directory_iterator(store.dir())) on_disk += e.file_size();
  EXPECT_EQ(on_disk, store.bytes());  // no temporary file left behind
  EXPECT_THROW(store.put(3, meta, "p", "u"), Error);
  EXPECT_THROW(store.putUpdates(4, meta, "u"), NotFoundError);
  store.erase(3);
  EXPECT_TRUE(std::filesystem::is_empty(store.dir()));
}

TEST(FrameCodec, PosedPointsAreTheWorldPointsOfTheStoredOnesWithTheirBox) {
  history::FramePoints points;
  points.quantised = {{1000, -2000, 3000}, {1001, -1990, 3005}, {-400, 20, 2500}};
  points.colors = {{{1, 2, 3}}, {{4, 5, 6}}, {{7, 8, 9}}};
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1.0, 2.0, 3.0).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(4.0, -5.0, 6.0);
  std::string raw;
  PointBatch batch;
  batch.points.assign(7, Eigen::Vector3f::Zero());  // a reused batch: sizes follow the frame
  const Eigen::AlignedBox3f box = history::decodePointsPosed(history::encodePoints(points, 1), "test", T, 0.001, raw,
                                                             batch);
  ASSERT_EQ(batch.points.size(), 3u);
  Eigen::AlignedBox3f expected;
  for (size_t i = 0; i < 3; ++i) {
    const Eigen::Vector3f p = (T * (points.quantised[i].cast<double>() * 0.001)).cast<float>();
    EXPECT_EQ(batch.points[i], p);
    expected.extend(p);
  }
  EXPECT_EQ(batch.colors, points.colors);
  EXPECT_EQ(box.min(), expected.min());
  EXPECT_EQ(box.max(), expected.max());
}

TEST(MapHistory, CorrectedMapEqualsTheMapBuiltFromScratchWithTheCorrectedPoses) {
  const MapConfig config = historyConfig();
  const auto frames = test::driftedRoomSweep(24, smallCamera(), 0.25, 3.0, config.history_quantum_m);
  MapAndReference m(config);  // the reference: the map built with the true poses
  for (const auto& f : frames) {
    m.history.integrate(f.batchAt(f.T_drifted), f.T_drifted);
    m.reference_history.integrate(f.batchAt(f.T_true), f.T_true);
  }
  const MapDifference before = compare(m.map, m.reference);
  const auto poses = truePoses(frames);
  const CorrectionSummary summary = m.history.correct(poses);
  const MapDifference after = compare(m.map, m.reference);
  std::printf("uncorrected: %zu blocks differ, state agreement %.4f; corrected: %zu blocks, %.4f (%zu moved, %zu "
              "replayed, %zu blocks rebuilt)\n",
              before.blocks, before.agreement(), after.blocks, after.agreement(), summary.frames_moved,
              summary.frames_replayed, summary.blocks_rebuilt);
  // Frame 0 has no drift; the drift of frame 1 (1.1 cm, 0.13 deg) is above the thresholds.
  EXPECT_EQ(summary.frames_moved, frames.size() - 1);
  EXPECT_EQ(summary.blocks_kept, 0u);
  EXPECT_EQ(after.blocks, 0u);
  EXPECT_EQ(after.voxels_differing, 0u);
  EXPECT_LT(before.agreement(), 0.9);  // the drifted map is wrong enough to matter
  EXPECT_FALSE(summary.delta.isEmpty());

  // A second, identical correction moves nothing.
  const CorrectionSummary again = m.history.correct(poses);
  EXPECT_EQ(again.frames_moved, 0u);
  EXPECT_TRUE(again.delta.isEmpty());
}

// A correction of a 20-frame sweep on one thread and on three (odd: uneven block ranges and a short
// last group of frames moved side by side) gives the same bits.
void expectTheSameCorrectedMapForOneAndThreeThreads(CorrectionMove move) {
  MapConfig one = historyConfig(move);
  one.num_threads = 1;
  MapConfig three = one;
  three.num_threads = 3;
  three.history_dir += "-three";
  const auto frames = test::driftedRoomSweep(20, smallCamera(), 0.25, 3.0, one.history_quantum_m);
  OccupancyMap map_one(one), map_three(three);
  MapHistory history_one(map_one), history_three(map_three);
  for (const auto& f : frames) {
    history_one.integrate(f.batchAt(f.T_drifted), f.T_drifted);
    history_three.integrate(f.batchAt(f.T_drifted), f.T_drifted);
  }
  const auto poses = truePoses(frames);
  EXPECT_EQ(history_three.movesAtOnce(), 3u);
  // Steps between which ingest goes on: three resamplings side by side, one march (on all threads).
  EXPECT_EQ(history_three.movesPerStep(), move == CorrectionMove::kResample ? 3u : 1u);
  const CorrectionSummary summary_one = history_one.correct(poses);
  const CorrectionSummary summary_three = history_three.correct(poses);
  EXPECT_EQ(summary_one.frames_moved, 19u);
  EXPECT_EQ(summary_three.frames_moved, 19u);
  EXPECT_EQ(summary_one.blocks_rebuilt, summary_three.blocks_rebuilt);
  EXPECT_EQ(summary_one.delta.changed_blocks, summary_three.delta.changed_blocks);
  const MapDifference d = compare(map_one, map_three);
  EXPECT_EQ(d.blocks, 0u);
  EXPECT_GT(d.voxels_known, 10000u);
}

// Frames marched side by side (moveFrames) and the replay's parallel rounds give the same bits for
// any thread count.
TEST(MapHistory, CorrectedMapIsTheSameForAnyThreadCount) {
  expectTheSameCorrectedMapForOneAndThreeThreads(CorrectionMove::kMarch);
}

TEST(MapHistory, FramesIntegratedBetweenTheStepsOfACorrectionAreReplayedToo) {
  const MapConfig config = historyConfig();
  const auto frames = test::driftedRoomSweep(24, smallCamera(), 0.25, 3.0, config.history_quantum_m);
  MapAndReference m(config);
  std::vector<CorrectedPose> poses;
  for (size_t i = 0; i < 18; ++i) {
    m.history.integrate(frames[i].batchAt(frames[i].T_drifted), frames[i].T_drifted);
    poses.push_back({frames[i].t_s, frames[i].T_true});
  }
  for (const auto& f : frames) m.reference_history.integrate(f.batchAt(f.T_true), f.T_true);
  // The last 6 frames arrive (with their true poses) while the correction of the first 18 runs.
  CorrectionPlan plan = m.history.planCorrection(poses);
  ASSERT_EQ(plan.moved.size(), 17u);
  size_t next = 0;
  for (size_t i = 0; i < plan.moved.size(); ++i) {
    m.history.moveFrame(plan, i);
    if (i % 3 == 0 && next < 6) {
      const auto& f = frames[18 + next++];
      m.history.integrate(f.batchAt(f.T_true), f.T_true);
    }
  }
  ASSERT_EQ(next, 6u);
  const CorrectionSummary summary = m.history.finishCorrection(plan);
  EXPECT_EQ(summary.frames_moved, 17u);
  EXPECT_EQ(compare(m.map, m.reference).blocks, 0u);
}

TEST(MapHistory, PartialCorrectionMovesOnlyTheFramesItCoversAndFramesWithoutPoseStay) {
  const MapConfig config = historyConfig();
  const auto frames = test::driftedRoomSweep(16, smallCamera(), 0.2, 2.0, config.history_quantum_m);
  MapAndReference m(config);
  // Frames 10-15 corrected; frame 3 integrated without a pose (as streamed points are).
  for (size_t i = 0; i < frames.size(); ++i) {
    const auto& f = frames[i];
    if (i == 3) {
      m.history.integrate(f.batchAt(f.T_drifted));
      m.reference_history.integrate(f.batchAt(f.T_drifted));
      continue;
    }
    m.history.integrate(f.batchAt(f.T_drifted), f.T_drifted);
    const Eigen::Isometry3d& T = i >= 10 ? f.T_true : f.T_drifted;
    m.reference_history.integrate(f.batchAt(T), T);
  }
  std::vector<CorrectedPose> poses;
  for (size_t i = 10; i < frames.size(); ++i) poses.push_back({frames[i].t_s, frames[i].T_true});
  const CorrectionSummary summary = m.history.correct(poses);
  EXPECT_EQ(summary.frames_moved, 6u);
  EXPECT_GT(summary.frames_replayed, 6u);  // earlier frames share blocks with the moved ones
  EXPECT_EQ(compare(m.map, m.reference).blocks, 0u);
}

TEST(MapHistory, InterpolatesBetweenCorrectedPosesWithinTheGap) {
  MapConfig config = historyConfig();
  const auto frames = test::driftedRoomSweep(9, smallCamera(), 0.1, 0.0, config.history_quantum_m);
  OccupancyMap map(config);
  MapHistory history(map);
  for (const auto& f : frames) history.integrate(f.batchAt(f.T_drifted), f.T_drifted);
  // Every other frame's pose, shifted by 1 m: the ones between are interpolated (gap 0.2 s).
  std::vector<CorrectedPose> poses;
  for (size_t i = 0; i < frames.size(); i += 2) {
    Eigen::Isometry3d T = frames[i].T_drifted;
    T.translation().x() += 1.0;
    poses.push_back({frames[i].t_s, T});
  }
  EXPECT_EQ(history.correct(poses).frames_moved, 9u);
  map.reset();
  history.clear();
  for (const auto& f : frames) history.integrate(f.batchAt(f.T_drifted), f.T_drifted);
  MapConfig tight = config;
  tight.correction_max_gap_s = 0.15;
  tight.history_dir += "-tight";  // gaps of 0.2 s are too long now: only the sampled frames move
  OccupancyMap map2(tight);
  MapHistory history2(map2);
  for (const auto& f : frames) history2.integrate(f.batchAt(f.T_drifted), f.T_drifted);
  EXPECT_EQ(history2.correct(poses).frames_moved, 5u);
}

TEST(MapHistory, StoreBeyondItsBudgetDropsTheOldestFramesAndKeepsTheirBlocks) {
  MapConfig config = historyConfig();
  config.history_max_mb = 1;
  const auto frames = test::driftedRoomSweep(30, smallCamera(), 0.2, 2.0, config.history_quantum_m);
  OccupancyMap map(config);
  MapHistory history(map);
  for (const auto& f : frames) history.integrate(f.batchAt(f.T_drifted), f.T_drifted);
  EXPECT_LT(history.numFrames(), frames.size());
  EXPECT_LE(history.storeBytes(), 1u << 20);
  const size_t bytes_on_disk = [&] {
    size_t total = 0;
    for (const auto& e : std::filesystem::directory_iterator(history.store().dir())) total += e.file_size();
    return total;
  }();
  EXPECT_EQ(bytes_on_disk, history.storeBytes());
  const CorrectionSummary summary = history.correct(truePoses(frames));
  EXPECT_EQ(summary.frames_moved, history.numFrames());
  EXPECT_GT(summary.blocks_kept, 0u);
}

TEST(MapHistory, RejectsPosesOutOfOrderOrNotRigid) {
  const MapConfig config = historyConfig();
  OccupancyMap map(config);
  MapHistory history(map);
  std::vector<CorrectedPose> poses(2);
  poses[0].t_s = 1.0;
  poses[1].t_s = 1.0;
  try {
    history.correct(poses);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "correction: pose 1 (t = 1.000000 s) must come after the previous pose (t = 1.000000 s)");
  }
  poses[1].t_s = 2.0;
  poses[1].T_world_pose.linear()(0, 0) = 2.0;
  try {
    history.correct(poses);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(),
                 "correction: pose 1 (t = 2.000000 s) must be a rigid transform (its rotation is not orthonormal with "
                 "determinant 1)");
  }
}

TEST(FrameStore, PutResampledKeepsTheMarchedUpdatesUntilTheNextMarch) {
  history::FrameStore store(historyConfig().history_dir, 1 << 20);
  history::FrameMeta meta;
  store.put(3, meta, "points", "marched");
  EXPECT_FALSE(store.isResampled(3));
  EXPECT_EQ(store.readMarched(3), "marched");
  store.putResampled(3, meta, "resampled 1");
  store.putResampled(3, meta, "resampled 2");  // from the same marched updates
  EXPECT_TRUE(store.isResampled(3));
  EXPECT_EQ(store.readUpdates(3), "resampled 2");
  EXPECT_EQ(store.readMarched(3), "marched");
  EXPECT_EQ(store.bytes(), 6u + 11u + 7u);
  const auto on_disk = [&] {
    size_t total = 0;
    for (const auto& e : std::filesystem::directory_iterator(store.dir())) total += e.file_size();
    return total;
  };
  EXPECT_EQ(on_disk(), store.bytes());
  store.putUpdates(3, meta, "marched again");  // a march: the marched updates from now on
  EXPECT_FALSE(store.isResampled(3));
  EXPECT_EQ(store.readMarched(3), "marched again");
  EXPECT_EQ(store.bytes(), 6u + 13u);
  EXPECT_EQ(on_disk(), store.bytes());
  store.putResampled(3, meta, "r");
  store.erase(3);
  EXPECT_TRUE(std::filesystem::is_empty(store.dir()));
}

// The resampled correction (map.correction_move: resample) against the map built from scratch with
// the true poses, as a loop closure corrects the end of a dive (the bench's tunnel: the odometry
// drifted over the last third of the frames): the bar (99 % of the voxels known in either in
// the same state), the reference's occupied voxels it makes free (what a planner would trust: at
// most the march's and a tenth of a percent of them), its occupied voxels near the true surfaces,
// the march's figures beside them. A camera whose rays are dense (at 3 m, 1.2 cm apart): where rays
// are a voxel apart the free sets are ragged, and the resampling errs at their every edge
// (docs/CORRECTIONS.md).
TEST(MapHistory, ResampledCorrectionAgreesWithTheMapBuiltFromScratch) {
  const MapConfig config = historyConfig(CorrectionMove::kResample);
  const PinholeCamera camera{.width = 320, .height = 240, .fx = 250.0, .fy = 250.0, .cx = 159.5, .cy = 119.5};
  const auto frames = test::driftedRoomSweep(24, camera, 0.25, 3.0, config.history_quantum_m);
  constexpr size_t kFirstDrifted = 16;
  MapAndReference m(config);
  MapConfig march_config = historyConfig(CorrectionMove::kMarch);
  march_config.history_dir += "-march";
  OccupancyMap marched(march_config);
  MapHistory marched_history(marched);
  for (size_t i = 0; i < frames.size(); ++i) {
    const auto& f = frames[i];
    const Eigen::Isometry3d& T = i < kFirstDrifted ? f.T_true : f.T_drifted;
    m.history.integrate(f.batchAt(T), T);
    marched_history.integrate(f.batchAt(T), T);
    m.reference_history.integrate(f.batchAt(f.T_true), f.T_true);
  }
  const test::MapAgreement before = test::compareStates(m.map, m.reference);
  const auto poses = truePoses(frames);
  const CorrectionSummary summary = m.history.correct(poses);
  marched_history.correct(poses);
  const test::MapAgreement after = test::compareStates(m.map, m.reference);
  const test::MapAgreement march = test::compareStates(marched, m.reference);
  const double near = test::occupiedNearSurfaces(m.map, test::driftedRoom(), config.voxel_size_m);
  const double near_reference = test::occupiedNearSurfaces(m.reference, test::driftedRoom(), config.voxel_size_m);
  std::printf(
      "agreement with the map from scratch: uncorrected %.4f, resampled %.4f, marched %.4f; of the reference's "
      "%llu occupied voxels the resampled map makes %llu free, the marched %llu; %llu unknown; occupied within "
      "a voxel of a true surface: resampled %.4f, reference %.4f\n",
      before.agreement(), after.agreement(), march.agreement(), static_cast<unsigned long long>(after.reference_occupied),
      static_cast<unsigned long long>(after.occupied_made_free), static_cast<unsigned long long>(march.occupied_made_free),
      static_cast<unsigned long long>(after.occupied_made_unknown), near, near_reference);
  EXPECT_EQ(summary.frames_moved, frames.size() - kFirstDrifted);
  EXPECT_LT(before.agreement(), 0.95);
  EXPECT_GE(after.agreement(), 0.99);
  EXPECT_EQ(march.agreement(), 1.0);
  EXPECT_LE(after.occupied_made_free, march.occupied_made_free + after.reference_occupied / 1000);
  EXPECT_GE(near, near_reference - 0.01);
  EXPECT_GT(after.reference_occupied, 10000u);
}

// Each correction resamples a frame from its marched updates and their pose, so corrections after
// one another land where one correction to the last poses lands, bit for bit; and a correction
// back to the poses the frames were marched at restores the map as it was.
TEST(MapHistory, RepeatedResampledCorrectionsStartFromTheMarchedUpdates) {
  const MapConfig config = historyConfig(CorrectionMove::kResample);
  const auto frames = test::driftedRoomSweep(16, smallCamera(), 0.25, 3.0, config.history_quantum_m);
  MapAndReference m(config);  // the reference: corrected once, straight to the true poses
  for (const auto& f : frames) {
    m.history.integrate(f.batchAt(f.T_drifted), f.T_drifted);
    m.reference_history.integrate(f.batchAt(f.T_drifted), f.T_drifted);
  }
  MapConfig as_integrated_config = config;
  as_integrated_config.history_dir += "-as-integrated";
  OccupancyMap as_integrated(as_integrated_config);
  MapHistory as_integrated_history(as_integrated);
  for (const auto& f : frames) as_integrated_history.integrate(f.batchAt(f.T_drifted), f.T_drifted);
  std::vector<CorrectedPose> halfway, drifted;
  for (const auto& f : frames) {
    Eigen::Isometry3d T = f.T_true;
    T.translation() = 0.5 * (f.T_true.translation() + f.T_drifted.translation());
    halfway.push_back({f.t_s, T});
    drifted.push_back({f.t_s, f.T_drifted});
  }
  const auto truth = truePoses(frames);
  EXPECT_EQ(m.history.correct(halfway).frames_moved, frames.size() - 1);
  EXPECT_EQ(m.history.correct(truth).frames_moved, frames.size() - 1);
  m.reference_history.correct(truth);
  const MapDifference d = compare(m.map, m.reference);
  EXPECT_EQ(d.blocks, 0u) << "of the blocks of " << d.voxels_known << " known voxels";
  EXPECT_GT(d.voxels_known, 10000u);

  EXPECT_EQ(m.history.correct(drifted).frames_moved, frames.size() - 1);
  const MapDifference back = compare(m.map, as_integrated);
  EXPECT_EQ(back.blocks, 0u) << "of the blocks of " << back.voxels_known << " known voxels";
}

// Frames resampled side by side give the same bits for any thread count.
TEST(MapHistory, ResampledCorrectionIsTheSameForAnyThreadCount) {
  expectTheSameCorrectedMapForOneAndThreeThreads(CorrectionMove::kResample);
}

}  // namespace
}  // namespace cenote::mapping
