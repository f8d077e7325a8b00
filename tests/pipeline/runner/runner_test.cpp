#include "pipeline/runner/runner.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <tuple>
#include <nlohmann/json.hpp>

#include "common/error.h"
#include "io/cloud/pcd_io.h"
#include "io/cloud/ply_io.h"
#include "pipeline/fusion/outlier_removal.h"
#include "pipeline/runner/bounded_queue.h"
#include "tests/support/plane_sequence.h"

namespace cenote::pipeline {
namespace {
namespace fs = std::filesystem;

struct Fixture {
  std::string dataset_dir, out_dir;
  std::unique_ptr<StereoDataset> dataset;
  io::Trajectory trajectory;
};

Fixture makeFixture(const std::string& name, const test::PlaneSequence& s = {}) {
  Fixture f;
  f.dataset_dir = testing::TempDir() + "/" + name + "_data";
  f.out_dir = testing::TempDir() + "/" + name + "_out";
  fs::remove_all(f.dataset_dir);
  fs::remove_all(f.out_dir);
  test::writeEurocPlaneSequence(f.dataset_dir, s);
  f.dataset = openDataset(f.dataset_dir);
  f.trajectory = cameraTrajectory(*f.dataset, "", "", PoseFrame::kAuto);
  return f;
}

// As config/default.yaml: with the left-right check, the left image's first columns (whose match
// lies left of the right image) do not become far-away points.
PipelineConfig smallConfig() {
  PipelineConfig c;
  c.stereo.num_disparities = 32;
  c.stereo.lr_check = true;
  c.stereo.invalidate_truncated = true;
  return c;
}

TEST(Runner, FusedPointsLieOnThePlaneAndEveryFrameIsCounted) {
  Fixture f = makeFixture("runner_plane");
  const std::atomic<bool> stop{false};
  size_t sunk = 0;
  Runner runner(smallConfig());
  const RunReport r = runner.run(*f.dataset, f.trajectory, f.out_dir, stop,
                                 [&](const PointBatch& b, const Eigen::Isometry3d&) { sunk += b.size(); });
  EXPECT_EQ(r.frames_in, 9u);
  EXPECT_EQ(r.frames_processed, 9u);
  EXPECT_EQ(r.frames_fused, 7u);  // a window of 3 emits from the third frame on
  EXPECT_EQ(r.skipped_no_pose + r.skipped_not_keyframe + r.skipped_unreadable, 0u);
  const io::PlyPoints cloud = io::readPly(f.out_dir + "/points.ply");
  ASSERT_GT(cloud.points.size(), 7u * 160 * 120 / 2) << "at least half the pixels fused";
  EXPECT_EQ(cloud.points.size(), r.points_written);
  EXPECT_EQ(sunk, r.points_written);
  size_t on_plane = 0;
  for (const auto& p : cloud.points) on_plane += std::abs(p.z() - 2.0f) < 0.05f;
  EXPECT_GT(static_cast<double>(on_plane) / cloud.points.size(), 0.97) << on_plane << " of " << cloud.points.size();
  EXPECT_EQ(r.stages.at("stereo").frames, 9u);
}

TEST(Runner, FramesWithoutPoseAreSkippedAndCountedNeverGuessed) {
  Fixture f = makeFixture("runner_no_pose");
  // Keep only the poses before frame 4.
  std::vector<io::StampedPose> early;
  for (const io::StampedPose& p : f.trajectory.poses())
    if (p.t_s < f.dataset->timestamp(4) - 0.02) early.push_back(p);
  const io::Trajectory partial(early, "partial");
  const std::atomic<bool> stop{false};
  const RunReport r = Runner(smallConfig()).run(*f.dataset, partial, f.out_dir, stop);
  EXPECT_EQ(r.skipped_no_pose, 5u);
  EXPECT_EQ(r.frames_processed, 4u);
}

TEST(Runner, KeyframeThresholdsSkipFramesThatBarelyMoved) {
  Fixture f = makeFixture("runner_keyframes");
  PipelineConfig c = smallConfig();
  c.run.keyframe_translation_m = 0.015;  // frames are 0.01 m apart: every second one is kept
  const std::atomic<bool> stop{false};
  const RunReport r = Runner(c).run(*f.dataset, f.trajectory, f.out_dir, stop);
  EXPECT_EQ(r.frames_processed, 5u);
  EXPECT_EQ(r.skipped_not_keyframe, 4u);
}

TEST(Runner, UnreadableImageSkipsOneFrameAndTheRestGoesOn) {
  Fixture f = makeFixture("runner_corrupt");
  const std::string victim = f.dataset_dir + "/mav0/cam1/data/" +
                             std::to_string(std::llround(f.dataset->timestamp(3) * 1e9)) + ".png";
  std::ofstream(victim, std::ios::trunc) << "not a png";
  const std::atomic<bool> stop{false};
  const RunReport r = Runner(smallConfig()).run(*f.dataset, f.trajectory, f.out_dir, stop);
  EXPECT_EQ(r.skipped_unreadable, 1u);
  EXPECT_EQ(r.frames_processed, 8u);
}

TEST(Runner, StopRequestEndsCleanlyWithTheOutputsWritten) {
  Fixture f = makeFixture("runner_stop");
  const std::atomic<bool> stop{true};
  const RunReport r = Runner(smallConfig()).run(*f.dataset, f.trajectory, f.out_dir, stop);
  EXPECT_TRUE(r.interrupted);
  EXPECT_EQ(r.frames_processed, 0u);
  EXPECT_TRUE(fs::exists(f.out_dir + "/points.ply"));
}

TEST(Runner, WithoutFusionEveryFrameGivesRawPointsAndDepthMapsAreWritten) {
  Fixture f = makeFixture("runner_raw");
  PipelineConfig c = smallConfig();
  c.run.fuse = false;
  c.run.write_depth = true;
  const std::atomic<bool> stop{false};
  const RunReport r = Runner(c).run(*f.dataset, f.trajectory, f.out_dir, stop);
  EXPECT_EQ(r.frames_fused, 9u);
  size_t maps = 0;
  for (const auto& e : fs::directory_iterator(f.out_dir + "/depth")) maps += e.path().string().ends_with(".depth.pfm");
  EXPECT_EQ(maps, 9u);
  // Named as the dataset's images, nanoseconds exactly.
  for (size_t i = 0; i < f.dataset->size(); ++i) {
    EXPECT_TRUE(fs::exists(f.out_dir + "/depth/" + f.dataset->frameName(i) + ".depth.pfm")) << f.dataset->frameName(i);
  }
}

TEST(Runner, VoxelDownsamplingKeepsExactlyOnePointPerOccupiedVoxel) {
  Fixture f = makeFixture("runner_voxel");
  const std::atomic<bool> stop{false};
  PipelineConfig c = smallConfig();
  Runner(c).run(*f.dataset, f.trajectory, f.out_dir + "_all", stop);
  c.run.points_voxel_m = 0.05;
  const RunReport r = Runner(c).run(*f.dataset, f.trajectory, f.out_dir, stop);
  auto key = [](const Eigen::Vector3f& p) {
    return std::make_tuple(std::floor(p.x() / 0.05), std::floor(p.y() / 0.05), std::floor(p.z() / 0.05));
  };
  std::set<std::tuple<float, float, float>> occupied, kept;
  for (const auto& p : io::readPly(f.out_dir + "_all/points.ply").points) occupied.insert(key(p));
  for (const auto& p : io::readPly(f.out_dir + "/points.ply").points) kept.insert(key(p));
  ASSERT_GT(occupied.size(), 100u) << "premise: two empty clouds would be equal too";
  EXPECT_EQ(r.points_written, occupied.size());
  EXPECT_EQ(kept.size(), r.points_written) << "two points in one voxel";
  EXPECT_EQ(kept, occupied);
}

TEST(Runner, PcdOutputHoldsThePointsOfThePlyOutput) {
  Fixture f = makeFixture("runner_pcd");
  const std::atomic<bool> stop{false};
  PipelineConfig c = smallConfig();
  Runner(c).run(*f.dataset, f.trajectory, f.out_dir + "_ply", stop);
  c.run.points_format = "pcd";
  const RunReport r = Runner(c).run(*f.dataset, f.trajectory, f.out_dir, stop);
  EXPECT_FALSE(fs::exists(f.out_dir + "/points.ply"));
  const io::PlyPoints ply = io::readPly(f.out_dir + "_ply/points.ply");
  const io::PcdPoints pcd = io::readPcd(f.out_dir + "/points.pcd");
  ASSERT_GT(ply.points.size(), 0u);
  EXPECT_EQ(r.points_written, ply.points.size());
  EXPECT_EQ(pcd.points, ply.points);
  EXPECT_EQ(pcd.colors, ply.colors);
}

TEST(Runner, OutlierRemovalFiltersEachFusedFrameBeforeTheFileAndTheMap) {
  Fixture f = makeFixture("runner_sor");
  const std::atomic<bool> stop{false};
  PipelineConfig c = smallConfig();
  std::vector<PointBatch> fused;
  Runner(c).run(*f.dataset, f.trajectory, f.out_dir + "_all", stop,
                [&](const PointBatch& b, const Eigen::Isometry3d&) { fused.push_back(b); });
  c.run.outlier_neighbours = 8;
  c.run.outlier_stddev_mul = 1.0;
  size_t sunk = 0;
  const RunReport r = Runner(c).run(*f.dataset, f.trajectory, f.out_dir, stop,
                                    [&](const PointBatch& b, const Eigen::Isometry3d&) { sunk += b.size(); });
  std::vector<Eigen::Vector3f> expected;
  for (const PointBatch& b : fused) {
    const PointBatch kept = removeStatisticalOutliers(b, 8, 1.0);
    expected.insert(expected.end(), kept.points.begin(), kept.points.end());
  }
  size_t all = 0;
  for (const PointBatch& b : fused) all += b.size();
  const io::PlyPoints cloud = io::readPly(f.out_dir + "/points.ply");
  EXPECT_EQ(cloud.points, expected) << "each frame filtered on its own, in order";
  EXPECT_EQ(r.points_written, expected.size());
  EXPECT_EQ(sunk, expected.size()) << "the map gets the filtered points";
  EXPECT_LT(expected.size(), all);
  Runner(c).run(*f.dataset, f.trajectory, f.out_dir + "_again", stop);
  EXPECT_EQ(io::readPly(f.out_dir + "_again/points.ply").points, cloud.points) << "not deterministic";
}

TEST(RunReport, JsonHasTheDocumentedKeys) {
  Fixture f = makeFixture("runner_json");
  const std::atomic<bool> stop{false};
  const RunReport r = Runner(smallConfig()).run(*f.dataset, f.trajectory, f.out_dir, stop);
  const nlohmann::json j = nlohmann::json::parse(r.toJson());
  for (const char* key : {"frames_in", "frames_processed", "fps", "stages", "peak_memory_mb", "frames_skipped"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  for (const char* stage : {"read_rectify", "stereo", "fusion", "output"}) {
    EXPECT_TRUE(j["stages"].contains(stage)) << stage;
    EXPECT_TRUE(j["stages"][stage].contains("median_ms"));
    EXPECT_TRUE(j["stages"][stage].contains("p95_ms"));
  }
}

TEST(RunConfig, DefaultsAreValidAndBadValuesAreNamed) {
  EXPECT_TRUE(PipelineConfig{}.validate().empty());
  RunConfig c;
  c.queue_depth = 0;
  c.pose_max_gap_s = -1;
  EXPECT_EQ(formatConfigErrors(c.validate()),
            "run.queue_depth = 0: must be in [1, 64]\nrun.pose_max_gap_s = -1: must be > 0");
  PipelineConfig bad;
  bad.run = c;
  EXPECT_THROW(Runner{bad}, Error);
  RunConfig points;
  points.points_format = "las";
  points.outlier_neighbours = -1;
  points.outlier_stddev_mul = 0.0;
  EXPECT_EQ(formatConfigErrors(points.validate()),
            "run.points_format = las: must be ply or pcd\nrun.outlier_neighbours = -1: must be >= 0 (0 = off)\n"
            "run.outlier_stddev_mul = 0: must be > 0");
}

TEST(PipelineConfig, DefaultYamlLoadsAndUnknownKeysAreErrors) {
  const PipelineConfig c = PipelineConfig::load(std::string(CENOTE_SOURCE_DIR) + "/config/default.yaml");
  EXPECT_TRUE(c.validate().empty()) << formatConfigErrors(c.validate());
  const std::string path = testing::TempDir() + "/typo.yaml";
  std::ofstream(path) << "run:\n  queue_dept: 3\n";
  try {
    PipelineConfig::load(path);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("run.queue_dept"), std::string::npos) << e.what();
  }
}

TEST(BoundedQueue, BlocksTheProducerWhenFullAndDrainsAfterClose) {
  BoundedQueue<int> q(2);
  EXPECT_TRUE(q.push(1));
  EXPECT_TRUE(q.push(2));
  std::atomic<bool> third_pushed{false}, producer_started{false};
  std::thread producer([&] {
    producer_started = true;
    q.push(3);
    third_pushed = true;
  });
  // Premise of the check below: the producer has reached push(), so "not pushed yet" is the
  // queue holding it back, not a thread that had not run yet.
  while (!producer_started.load()) std::this_thread::yield();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_FALSE(third_pushed.load()) << "a full queue must hold the producer back";
  EXPECT_EQ(q.pop().value(), 1);
  producer.join();
  EXPECT_TRUE(third_pushed.load());
  q.close();
  EXPECT_FALSE(q.push(4));
  EXPECT_EQ(q.pop().value(), 2);
  EXPECT_EQ(q.pop().value(), 3);
  EXPECT_FALSE(q.pop().has_value());
}

}  // namespace
}  // namespace cenote::pipeline
