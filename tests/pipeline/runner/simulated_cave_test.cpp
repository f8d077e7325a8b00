// End to end on the simulator: a 30-frame cave dive written as an EuRoC dataset, run through the
// whole pipeline with config/default.yaml, and the fused points compared with the ground-truth
// surface those frames see (the left camera's exact depth, back-projected).
#include <gtest/gtest.h>

#include <filesystem>
#include <limits>

#include "eval/cloud/cloud_metrics.h"
#include "eval/cloud/voxel_downsample.h"
#include "pipeline/fusion/back_projection.h"
#include "io/image/image_io.h"
#include "io/cloud/ply_io.h"
#include "pipeline/runner/runner.h"
#include "sim/sim_dataset.h"

namespace cenote::pipeline {
namespace {
namespace fs = std::filesystem;

TEST(SimulatedCave, FusedPointsMatchTheSeenSurfaceWithin5cm) {
  const std::string dir = testing::TempDir() + "/sim_cave_30";
  fs::remove_all(dir);
  sim::SimConfig sim_config;
  sim_config.scene = sim::SimSceneKind::kCave;
  sim_config.num_frames = 30;
  const sim::Simulator simulator(sim_config);
  sim::writeSimDataset(simulator, dir + "/data");

  const auto dataset = openDataset(dir + "/data");
  PipelineConfig config = PipelineConfig::load(std::string(CENOTE_SOURCE_DIR) + "/config/default.yaml");
  // 8 paths: the rig light washes out the cave floor near the camera, and a textureless slanted
  // floor is where one top-down pass (4 paths) fails: 11 % bad-1 there against 3 % with the
  // bottom-up paths (precision 85 % vs 93 % at 5 cm over the dive).
  config.stereo.num_paths = 8;
  const io::Trajectory trajectory = cameraTrajectory(*dataset, "", "", config.run.pose_frame);
  const std::atomic<bool> stop{false};
  const RunReport report = Runner(config).run(*dataset, trajectory, dir + "/out", stop);
  ASSERT_EQ(report.frames_processed, 30u);
  const io::PlyPoints ours = io::readPly(dir + "/out/points.ply");

  // The surface seen by the fused reference frames (all but the first and last with N_f = 3), within
  // the pipeline's working range (fusion.max_depth_m); precision is judged against the surface
  // seen a little beyond it, so that a point fused just inside the range is not counted wrong.
  PointBatch truth_batch;
  std::vector<Eigen::Vector3f> truth, truth_beyond;
  const float max_depth = static_cast<float>(config.fusion.max_depth_m);
  const int half = config.fusion.num_views / 2;
  for (int i = half; i < simulator.numFrames() - half; ++i) {
    DepthFrame frame;
    const cv::Mat depth = io::readPfm(dir + "/data/groundtruth/depth/" + std::to_string(simulator.frameTimeNs(i)) + ".pfm");
    const PinholeCamera& c = simulator.rig().camera;
    frame.K << c.fx, 0.0, c.cx, 0.0, c.fy, c.cy, 0.0, 0.0, 1.0;
    frame.T_world_cam = simulator.T_world_cam0(simulator.frameTimeS(i));
    for (const auto& [limit, cloud] : {std::pair{max_depth, &truth}, std::pair{1.25f * max_depth, &truth_beyond}}) {
      frame.depth = depth.clone();
      frame.depth.setTo(std::numeric_limits<float>::infinity(), depth > limit);
      backProject(frame, truth_batch);
      cloud->insert(cloud->end(), truth_batch.points.begin(), truth_batch.points.end());
    }
  }
  // 1 cm voxels on both sides, as the paper's evaluation does (at 1 mm there).
  const auto source = eval::voxelDownsample(ours.points, 0.01);
  const auto target = eval::voxelDownsample(truth, 0.01);
  const auto target_beyond = eval::voxelDownsample(truth_beyond, 0.01);
  eval::CloudEvaluationOptions options;
  options.threshold_m = 0.05;
  const eval::CloudEvaluation e = eval::evaluateDistances(eval::nearestDistances(source, target_beyond),
                                                          eval::nearestDistances(target, source), options);
  std::cout << "simulated cave, 30 frames, surface within " << max_depth << " m: " << source.size() << " fused points vs "
            << target.size() << " surface points at 1 cm: precision " << 100 * e.precision << " %, recall "
            << 100 * e.recall << " % at 5 cm; accuracy " << e.accuracy_m << " m, completeness " << e.completeness_m
            << " m\n";
  EXPECT_GE(e.precision, 0.90);
  EXPECT_GE(e.recall, 0.90);
}

}  // namespace
}  // namespace cenote::pipeline
