// Simulator ground truth: depth on the mesh, consistency between frames, determinism, and the
// files that the dataset readers depend on.
#include "sim/simulator.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <opencv2/calib3d.hpp>

#include "pipeline/calibration/stereo_calibration.h"
#include "io/image/image_io.h"
#include "io/cloud/ply_io.h"
#include "sim/rounded_path.h"
#include "sim/sim_dataset.h"
#include "io/trajectory/tum_trajectory.h"

namespace cenote::sim {
namespace {

namespace fs = std::filesystem;

SimConfig smallConfig(SimSceneKind scene, int frames = 6) {
  SimConfig c;
  c.scene = scene;
  c.num_frames = frames;
  c.width_px = 400;
  c.height_px = 300;
  return c;
}

Eigen::Vector3d backProject(const Simulator& sim, const Eigen::Isometry3d& T_world_cam, int x, int y, double z) {
  const PinholeCamera& cam = sim.rig().camera;
  return T_world_cam * Eigen::Vector3d((x - cam.cx) / cam.fx * z, (y - cam.cy) / cam.fy * z, z);
}

class SimulatorScene : public ::testing::TestWithParam<SimSceneKind> {};

TEST_P(SimulatorScene, DepthBackProjectedWithThePoseLiesOnTheMeshWithinOneMillimetre) {
  const Simulator sim(smallConfig(GetParam()));
  for (int index : {0, 5}) {
    const SimFrame frame = sim.renderFrame(index);
    int checked = 0, finite = 0;
    for (int y = 3; y < frame.depth.rows; y += 17) {
      for (int x = 5; x < frame.depth.cols; x += 23) {
        const float z = frame.depth.at<float>(y, x);
        if (!std::isfinite(z)) continue;
        ++finite;
        const Eigen::Vector3d p = backProject(sim, frame.T_world_cam0, x, y, z);
        const double d = distanceToMesh(sim.scene().mesh, p, 0.01);
        EXPECT_LT(d, 1e-3) << toString(GetParam()) << " frame " << index << " pixel (" << x << ", " << y
                           << "), depth " << z << " m: " << d << " m from the mesh";
        ++checked;
      }
    }
    EXPECT_GT(finite, 200) << "too few pixels with a surface";
    EXPECT_GT(checked, 200);
  }
}

TEST_P(SimulatorScene, TwoFramesDepthsAgreeUnderTheirRelativePose) {
  const Simulator sim(smallConfig(GetParam()));
  const SimFrame a = sim.renderFrame(0), b = sim.renderFrame(4);
  const PinholeCamera& cam = sim.rig().camera;
  const Eigen::Isometry3d T_b_a = b.T_world_cam0.inverse() * a.T_world_cam0;
  int compared = 0, agree = 0;
  for (int y = 0; y < a.depth.rows; y += 3) {
    for (int x = 0; x < a.depth.cols; x += 3) {
      const float z = a.depth.at<float>(y, x);
      if (!std::isfinite(z)) continue;
      const Eigen::Vector3d p_b =
          T_b_a * Eigen::Vector3d((x - cam.cx) / cam.fx * z, (y - cam.cy) / cam.fy * z, z);
      if (p_b.z() <= 0.1) continue;
      const int u = static_cast<int>(std::lround(cam.fx * p_b.x() / p_b.z() + cam.cx));
      const int v = static_cast<int>(std::lround(cam.fy * p_b.y() / p_b.z() + cam.cy));
      if (u < 0 || v < 0 || u >= cam.width || v >= cam.height) continue;
      const float zb = b.depth.at<float>(v, u);
      if (!std::isfinite(zb)) continue;
      ++compared;
      // Within half a pixel of the projection the surface may tilt; 2 % of depth allows for that.
      if (std::abs(zb - p_b.z()) < 0.02 * p_b.z()) ++agree;
    }
  }
  ASSERT_GT(compared, 1000) << toString(GetParam());
  EXPECT_GT(static_cast<double>(agree) / compared, 0.95)
      << toString(GetParam()) << ": " << agree << " of " << compared << " reprojected depths agree";
}

TEST_P(SimulatorScene, OutputIsBitIdenticalForOneAndTwoThreads) {
  const Simulator sim(smallConfig(GetParam()));
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  const SimFrame one = sim.renderFrame(3);
  omp_set_num_threads(2);
  const SimFrame two = sim.renderFrame(3);
  omp_set_num_threads(saved);
  auto same = [](const cv::Mat& p, const cv::Mat& q) {
    return p.size() == q.size() && p.type() == q.type() &&
           std::memcmp(p.data, q.data, p.total() * p.elemSize()) == 0;
  };
  EXPECT_TRUE(same(one.left, two.left));
  EXPECT_TRUE(same(one.right, two.right));
  EXPECT_TRUE(same(one.depth, two.depth));
  EXPECT_TRUE(same(one.left_triangles, two.left_triangles));
}

INSTANTIATE_TEST_SUITE_P(Scenes, SimulatorScene,
                         ::testing::Values(SimSceneKind::kCave, SimSceneKind::kReef, SimSceneKind::kWreck),
                         [](const auto& info) { return std::string(toString(info.param)); });

TEST(Simulator, SameSeedSameImagesOtherSeedOtherImages) {
  SimConfig c = smallConfig(SimSceneKind::kReef, 2);
  const SimFrame a = Simulator(c).renderFrame(1);
  const SimFrame b = Simulator(c).renderFrame(1);
  c.seed = 2;
  const SimFrame other = Simulator(c).renderFrame(1);
  EXPECT_EQ(cv::norm(a.left, b.left, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(a.left, other.left, cv::NORM_L1), 0.0);
}

TEST(Simulator, ExposureRatioDarkensTheRightImage) {
  SimConfig c = smallConfig(SimSceneKind::kWreck, 1);
  c.exposure_ratio = 0.5;
  const SimFrame frame = Simulator(c).renderFrame(0);
  EXPECT_LT(cv::mean(frame.right)[1], 0.85 * cv::mean(frame.left)[1]);
}

TEST(Simulator, DistortedDepthLiesOnTheMeshAlongTheUndistortedRay) {
  SimConfig c = smallConfig(SimSceneKind::kCave, 1);
  c.k1 = -0.12;
  c.k2 = 0.02;
  const Simulator sim(c);
  const SimFrame frame = sim.renderFrame(0);
  const pipeline::StereoCalibration calib = sim.calibration();
  int checked = 0, finite = 0;
  for (int y = 0; y < frame.depth.rows; ++y) {
    for (int x = 0; x < frame.depth.cols; ++x) finite += std::isfinite(frame.depth.at<float>(y, x)) ? 1 : 0;
  }
  // The cave is closed: every pixel sees a wall. Where the walls' triangles are smaller than a
  // pixel (far down the tunnel) some rays stay unresolved and carry no ground truth (simulator.h).
  EXPECT_GT(finite, 0.8 * frame.depth.total());
  for (int y = 2; y < frame.depth.rows; y += 13) {
    for (int x = 1; x < frame.depth.cols; x += 17) {
      const float z = frame.depth.at<float>(y, x);
      if (!std::isfinite(z)) continue;
      std::vector<cv::Point2d> in{{static_cast<double>(x), static_cast<double>(y)}}, out;
      cv::undistortPoints(in, out, cv::Mat(calib.left.K), calib.left.distortion, cv::noArray(), cv::noArray(),
                          cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-14));
      const Eigen::Vector3d p = frame.T_world_cam0 * Eigen::Vector3d(out[0].x * z, out[0].y * z, z);
      EXPECT_LT(distanceToMesh(sim.scene().mesh, p, 0.01), 1e-3) << "pixel (" << x << ", " << y << ")";
      ++checked;
    }
  }
  EXPECT_GT(checked, 50);
}

TEST(RoundedPath, IsContinuousAndClosed) {
  const RoundedPath path({{0, 0}, {4, 0}, {4, 2}, {0, 2}}, 0.5);
  EXPECT_NEAR(path.length_m(), 2 * (4 + 2) - 8 * 0.5 + 2 * M_PI * 0.5, 1e-9);
  for (double s = 0; s < path.length_m(); s += 0.01) {
    EXPECT_NEAR((path.position(s + 0.01) - path.position(s)).norm(), 0.01, 1e-6) << "s = " << s;
    EXPECT_NEAR(path.tangent(s).norm(), 1.0, 1e-9);
  }
  EXPECT_NEAR((path.position(path.length_m()) - path.position(0)).norm(), 0.0, 1e-9);
}

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

  const pipeline::StereoCalibration rig =
      pipeline::readEurocSensorPair(dir_ + "/mav0/cam0/sensor.yaml", dir_ + "/mav0/cam1/sensor.yaml");
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
  for (const io::StampedPose& cam : cams.poses()) {
    const auto body = bodies.lookup(cam.t_s, 1e-6);  // 200 Hz is a multiple of 15 Hz's thirds? not always
    if (!body) continue;
    const Eigen::Matrix4d chained = body->T_world_cam.matrix() * T_body_cam;
    EXPECT_LT((chained - cam.T_world_cam.matrix()).norm(), 1e-6) << "t = " << cam.t_s;
  }
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
