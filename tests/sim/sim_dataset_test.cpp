// The files of a simulated dive that the dataset readers depend on.
#include "sim/sim_dataset.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "io/cloud/ply_io.h"
#include "io/image/image_io.h"
#include "io/trajectory/tum_trajectory.h"
#include "pipeline/calibration/stereo_calibration.h"
#include "sim/scene_mesh.h"
#include "sim/simulator.h"
#include "tests/sim/support/small_config.h"

namespace cenote::sim {
namespace {

namespace fs = std::filesystem;

using test::smallConfig;

class SimDataset : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = (fs::temp_directory_path() / ("cenote_sim_test_" + std::to_string(::getpid()))).string();
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string dir_;
};

TEST_F(SimDataset, SensorYamlReadsBackWithTheBaselineAndPosesChainThroughTheExtrinsics) {
  SimConfig c = smallConfig(SimSceneKind::kCave, 3);
  c.width_px = 160;
  c.height_px = 120;
  c.baseline_m = 0.15;
  const Simulator sim(c);
  const SimDatasetSummary summary = writeSimDataset(sim, dir_);
  EXPECT_EQ(summary.frames, 3);
  EXPECT_GT(summary.surface_points, 1000u);

  const pipeline::StereoCalibration rig = pipeline::readEurocSensorPair(dir_ + "/mav0/cam0/sensor.yaml",
                                                                        dir_ + "/mav0/cam1/sensor.yaml");
  EXPECT_EQ(rig.image_size, cv::Size(160, 120));
  EXPECT_NEAR(cv::norm(rig.T), 0.15, 1e-9);
  EXPECT_NEAR(rig.T[0], -0.15, 1e-9);  // right camera on the left camera's +x
  EXPECT_NEAR(cv::norm(rig.R - cv::Matx33d::eye()), 0.0, 1e-9);
  EXPECT_NEAR(rig.left.K(0, 0), sim.rig().camera.fx, 1e-9);
  const cv::Matx44d T_BS = pipeline::readEurocBodyFromSensor(dir_ + "/mav0/cam0/sensor.yaml");
  EXPECT_NEAR(std::sqrt(T_BS(0, 3) * T_BS(0, 3) + T_BS(1, 3) * T_BS(1, 3) + T_BS(2, 3) * T_BS(2, 3)), 0.05, 0.005);

  const pipeline::StereoCalibration calib = pipeline::readStereoCalibration(dir_ + "/groundtruth/calibration.yaml");
  EXPECT_NEAR(calib.T[0], -0.15, 1e-9);

  // cam0.tum = body ground truth x T_BS at the image times.
  const io::TumTrajectory cams = io::TumTrajectory::read(dir_ + "/groundtruth/cam0.tum");
  const io::TumTrajectory bodies = io::TumTrajectory::read(dir_ + "/groundtruth/body.tum");
  ASSERT_EQ(cams.size(), 3u);
  Eigen::Matrix4d T_body_cam;
  for (int r = 0; r < 4; ++r)
    for (int k = 0; k < 4; ++k) T_body_cam(r, k) = T_BS(r, k);
  int chained_checked = 0;
  for (const io::StampedPose& cam : cams.poses()) {
    const auto body = bodies.lookup(cam.t_s, 1e-6);  // 200 Hz is a multiple of 15 Hz's thirds? not always
    if (!body) continue;
    const Eigen::Matrix4d chained = body->T_world_cam.matrix() * T_body_cam;
    EXPECT_LT((chained - cam.T_world_cam.matrix()).norm(), 1e-6) << "t = " << cam.t_s;
    ++chained_checked;
  }
  // The first image is at a body sample (0.1 s after the first, 200 Hz): at least it is checked.
  EXPECT_GE(chained_checked, 1) << "no image time has a body pose within 1 us: nothing was chained";
  EXPECT_NEAR(cams.poses()[1].t_s - cams.poses()[0].t_s, 1.0 / 15.0, 1e-6);

  // Counts and headers of the EuRoC files.
  auto lines = [](const std::string& path) {
    std::ifstream in(path);
    std::vector<std::string> out;
    for (std::string line; std::getline(in, line);) out.push_back(line);
    return out;
  };
  const auto cam0 = lines(dir_ + "/mav0/cam0/data.csv");
  ASSERT_EQ(cam0.size(), 4u);
  EXPECT_EQ(cam0[0], "#timestamp [ns],filename");
  EXPECT_EQ(cam0[1], "1700000000000000000,1700000000000000000.png");
  EXPECT_EQ(lines(dir_ + "/mav0/cam1/data.csv"), cam0);
  const auto gt = lines(dir_ + "/mav0/state_groundtruth_estimate0/data.csv");
  EXPECT_EQ(gt[0].rfind("#timestamp, p_RS_R_x [m]", 0), 0u);
  // 200 Hz from 0.1 s before the first image to 0.1 s after the last (2/15 s).
  EXPECT_EQ(gt.size(), 1u + static_cast<size_t>(std::lround((0.2 + 2.0 / 15.0) * 200.0)) + 1u);
  for (int i = 0; i < 3; ++i) {
    const std::string name = std::to_string(sim.frameTimeNs(i));
    const cv::Mat left = io::readImage(dir_ + "/mav0/cam0/data/" + name + ".png", cv::IMREAD_UNCHANGED);
    EXPECT_EQ(left.type(), CV_8UC3);
    EXPECT_EQ(left.size(), cv::Size(160, 120));
    EXPECT_TRUE(fs::exists(dir_ + "/mav0/cam1/data/" + name + ".png"));
    const cv::Mat depth = io::readPfm(dir_ + "/groundtruth/depth/" + name + ".pfm");
    EXPECT_EQ(depth.type(), CV_32FC1);
  }
  const io::PlyPoints surface = io::readPly(dir_ + "/groundtruth/surface.ply");
  EXPECT_EQ(surface.points.size(), summary.surface_points);
  // Every surface point is on the mesh.
  for (size_t i = 0; i < surface.points.size(); i += surface.points.size() / 50) {
    EXPECT_LT(distanceToMesh(sim.scene().mesh, surface.points[i].cast<double>(), 0.01), 1e-4);
  }
}

}  // namespace
}  // namespace cenote::sim
