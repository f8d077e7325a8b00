// Simulator ground truth: depth on the mesh, consistency between frames, determinism.
#include "sim/simulator.h"
#include "tests/sim/support/small_config.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/calib3d.hpp>

namespace cenote::sim {
namespace {

namespace fs = std::filesystem;

using test::smallConfig;

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
        EXPECT_LT(d, 1e-3) << toString(GetParam()) << " frame " << index << " pixel (" << x << ", " << y << "), depth " << z
                           << " m: " << d << " m from the mesh";
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
      const Eigen::Vector3d p_b = T_b_a * Eigen::Vector3d((x - cam.cx) / cam.fx * z, (y - cam.cy) / cam.fy * z, z);
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
    return p.size() == q.size() && p.type() == q.type() && std::memcmp(p.data, q.data, p.total() * p.elemSize()) == 0;
  };
  // Premise: there is something to compare (two empty images are the same bytes too).
  ASSERT_EQ(one.left.size(), cv::Size(400, 300)) << toString(GetParam());
  ASSERT_EQ(one.depth.size(), one.left.size()) << toString(GetParam());
  ASSERT_GT(cv::countNonZero(one.left.reshape(1)), 0) << toString(GetParam()) << ": black image";
  ASSERT_GT(cv::countNonZero(one.depth < std::numeric_limits<float>::infinity()), 0)
      << toString(GetParam()) << ": no depth";
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
  ASSERT_FALSE(a.left.empty());
  ASSERT_GT(cv::countNonZero(a.left.reshape(1)), 0) << "black image";
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

}  // namespace
}  // namespace cenote::sim
