#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "common/error.h"
#include "pipeline/dataset/euroc_dataset.h"
#include "pipeline/dataset/kitti_dataset.h"
#include "pipeline/runner/runner.h"
#include "tests/support/plane_sequence.h"

namespace cenote::pipeline {
namespace {
namespace fs = std::filesystem;

std::string freshDir(const std::string& name) {
  const std::string dir = testing::TempDir() + "/" + name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(EurocDataset, ReadsFramesTimestampsCalibrationAndExtrinsics) {
  const std::string dir = freshDir("euroc_fixture");
  test::PlaneSequence s;
  test::writeEurocPlaneSequence(dir, s);
  const auto dataset = openDataset(dir);
  ASSERT_EQ(dataset->size(), 9u);
  EXPECT_NEAR(dataset->timestamp(0), 100.0, 1e-9);
  EXPECT_NEAR(dataset->timestamp(3), 100.2, 1e-9);
  EXPECT_DOUBLE_EQ(dataset->calibration().left.K(0, 0), 300.0);
  EXPECT_NEAR(cv::norm(dataset->calibration().T), 0.1, 1e-12);
  EXPECT_NEAR(dataset->T_body_cam().translation().x(), 0.05, 1e-12);
  const StereoFrame frame = dataset->load(2);
  EXPECT_EQ(frame.left.size(), cv::Size(160, 120));
  ASSERT_TRUE(dataset->defaultTrajectory());
  EXPECT_TRUE(dataset->defaultTrajectory()->describes_body);
}

TEST(EurocDataset, CameraTrajectoryComposesBodyPosesWithTheExtrinsics) {
  const std::string dir = freshDir("euroc_traj");
  test::PlaneSequence s;
  test::writeEurocPlaneSequence(dir, s);
  const auto dataset = openDataset(dir);
  const io::Trajectory camera = cameraTrajectory(*dataset, "", "", PoseFrame::kAuto);
  // Frame 4 at t = 100 + 4/15 s: the camera is at 0.15 m/s * 4/15 s = 0.04 m.
  const auto pose = camera.poseAt(dataset->timestamp(4), 0.1);
  ASSERT_TRUE(pose);
  EXPECT_NEAR(pose->translation().x(), 0.04, 1e-9);
  // Forcing "camera" skips the extrinsics: the body's own position comes out.
  const io::Trajectory as_camera = cameraTrajectory(*dataset, "", "", PoseFrame::kCamera);
  EXPECT_NEAR(as_camera.poseAt(dataset->timestamp(4), 0.1)->translation().x(), 0.04 - 0.05, 1e-9);
}

TEST(EurocDataset, UnpairedImagesAreLeftOutAndCounted) {
  const std::string dir = freshDir("euroc_unpaired");
  test::PlaneSequence s;
  test::writeEurocPlaneSequence(dir, s);
  // Drop frame 5 from the right camera's list.
  const fs::path csv = fs::path(dir) / "mav0" / "cam1" / "data.csv";
  std::ifstream in(csv);
  std::string text, line;
  for (int i = 0; std::getline(in, line); ++i)
    if (i != 6) text += line + "\n";
  in.close();
  std::ofstream(csv) << text;
  EurocDataset dataset(dir);
  EXPECT_EQ(dataset.size(), 8u);
  EXPECT_EQ(dataset.unpairedFrames(), 1u);
}

TEST(EurocDataset, MalformedCsvAndMissingImagesAreClearErrors) {
  const std::string dir = freshDir("euroc_bad");
  test::PlaneSequence s;
  test::writeEurocPlaneSequence(dir, s);
  std::ofstream(fs::path(dir) / "mav0" / "cam0" / "data.csv", std::ios::app) << "12x,abc.png\n";
  try {
    EurocDataset dataset(dir);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cam0/data.csv:11: '12x' is not a timestamp"), std::string::npos) << e.what();
  }
  const std::string dir2 = freshDir("euroc_missing_image");
  test::writeEurocPlaneSequence(dir2, s);
  EurocDataset dataset(dir2);
  fs::remove(fs::path(dir2) / "mav0" / "cam0" / "data" / (std::to_string(std::llround(dataset.timestamp(1) * 1e9)) + ".png"));
  EXPECT_THROW(dataset.load(1), Error);
}

TEST(StereoDataset, UnknownLayoutIsAnErrorSayingWhatWasExpected) {
  const std::string dir = freshDir("not_a_dataset");
  try {
    openDataset(dir);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("unknown layout"), std::string::npos);
  }
  EXPECT_THROW(openDataset(dir + "/absent"), Error);
}

TEST(KittiDataset, ReadsSequenceCalibrationTimesAndGroundTruth) {
  const std::string dir = freshDir("kitti_fixture");
  test::PlaneSequence s;
  test::writeKittiPlaneSequence(dir, s);
  const auto dataset = openDataset(dir + "/sequences/00");
  ASSERT_EQ(dataset->size(), 9u);
  EXPECT_NEAR(dataset->timestamp(3), 0.2, 1e-9);
  EXPECT_TRUE(dataset->calibration().rectified);
  EXPECT_NEAR(dataset->calibration().rectified_geometry.baseline_m, 0.1, 1e-9);
  EXPECT_NEAR(dataset->T_body_cam().translation().norm(), 0.0, 1e-12);  // grey camera 0 is the reference
  const auto gt = dataset->defaultTrajectory();
  ASSERT_TRUE(gt);
  const io::Trajectory camera = cameraTrajectory(*dataset, "", "", PoseFrame::kAuto);
  EXPECT_NEAR(camera.poseAt(dataset->timestamp(2), 0.2)->translation().x(), 0.02, 1e-6);
}

}  // namespace
}  // namespace cenote::pipeline
