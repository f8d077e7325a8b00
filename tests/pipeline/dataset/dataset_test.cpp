#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

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

// freshDir(name) holding the EuRoC plane sequence (tests/support/plane_sequence.h).
std::string freshEurocSequence(const std::string& name) {
  const std::string dir = freshDir(name);
  test::writeEurocPlaneSequence(dir, test::PlaneSequence{});
  return dir;
}

TEST(EurocDataset, ReadsFramesTimestampsCalibrationAndExtrinsics) {
  const std::string dir = freshEurocSequence("euroc_fixture");
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
  const std::string dir = freshEurocSequence("euroc_traj");
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
  const std::string dir = freshEurocSequence("euroc_unpaired");
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
  const std::string dir = freshEurocSequence("euroc_bad");
  std::ofstream(fs::path(dir) / "mav0" / "cam0" / "data.csv", std::ios::app) << "12x,abc.png\n";
  try {
    EurocDataset dataset(dir);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cam0/data.csv:11: '12x' is not a timestamp"), std::string::npos) << e.what();
  }
  const std::string dir2 = freshEurocSequence("euroc_missing_image");
  EurocDataset dataset(dir2);
  fs::remove(fs::path(dir2) / "mav0" / "cam0" / "data" /
             (std::to_string(std::llround(dataset.timestamp(1) * 1e9)) + ".png"));
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

// A KITTI odometry sequence written by hand from the format (devkit readme): calib.txt with the
// P0..P3 rows of sequence 00, times.txt with the real spacing (about 0.1036 s) and jitter,
// poses/00.txt with 3x4 [R | t] rows of camera 0 (a car driving 8.5 m/s along z, turning 0.2 rad/s),
// and one colour pair (image_2 / image_3, 1241x376) for the calibration's image size.
struct KittiLike {
  std::string root, sequence, poses;
  std::vector<double> times;
};

Eigen::Isometry3d kittiCam0Pose(double t_s) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(0.2 * t_s, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.3 * t_s * t_s, 0.0, 8.5 * t_s);
  return T;
}

KittiLike writeKittiLike(const std::string& name, int frames = 20) {
  KittiLike k;
  k.root = freshDir(name);
  k.sequence = k.root + "/sequences/00";
  fs::create_directories(k.sequence + "/image_2");
  fs::create_directories(k.sequence + "/image_3");
  fs::create_directories(k.root + "/poses");
  std::ofstream(k.sequence + "/calib.txt")
      << "P0: 7.188560000000e+02 0.000000000000e+00 6.071928000000e+02 0.000000000000e+00 0.000000000000e+00 "
         "7.188560000000e+02 1.852157000000e+02 0.000000000000e+00 0.000000000000e+00 0.000000000000e+00 "
         "1.000000000000e+00 0.000000000000e+00\n"
      << "P1: 7.188560000000e+02 0.000000000000e+00 6.071928000000e+02 -3.861448000000e+02 0.000000000000e+00 "
         "7.188560000000e+02 1.852157000000e+02 0.000000000000e+00 0.000000000000e+00 0.000000000000e+00 "
         "1.000000000000e+00 0.000000000000e+00\n"
      << "P2: 7.188560000000e+02 0.000000000000e+00 6.071928000000e+02 4.538225000000e+01 0.000000000000e+00 "
         "7.188560000000e+02 1.852157000000e+02 -1.130887000000e-01 0.000000000000e+00 0.000000000000e+00 "
         "1.000000000000e+00 3.779761000000e-03\n"
      << "P3: 7.188560000000e+02 0.000000000000e+00 6.071928000000e+02 -3.372877000000e+02 0.000000000000e+00 "
         "7.188560000000e+02 1.852157000000e+02 2.369057000000e+00 0.000000000000e+00 0.000000000000e+00 "
         "1.000000000000e+00 4.915215000000e-03\n";
  std::ofstream times(k.sequence + "/times.txt");
  std::ofstream poses(k.root + "/poses/00.txt");
  for (int i = 0; i < frames; ++i) {
    // 0.1036 s apart with up to +-0.4 ms of jitter (a fixed pattern), as KITTI's times.txt.
    const double t = i == 0 ? 0.0 : 0.1036 * i + 0.0004 * std::sin(1.7 * i);
    k.times.push_back(t);
    char line[64];
    std::snprintf(line, sizeof(line), "%.6e\n", t);
    times << line;
    const Eigen::Isometry3d T = kittiCam0Pose(t);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) {
        std::snprintf(line, sizeof(line), "%s%.9e", r + c == 0 ? "" : " ", T.matrix()(r, c));
        poses << line;
      }
    }
    poses << "\n";
  }
  k.poses = k.root + "/poses/00.txt";
  const cv::Mat image(376, 1241, CV_8UC3, cv::Scalar(90, 120, 150));
  cv::imwrite(k.sequence + "/image_2/000000.png", image);
  cv::imwrite(k.sequence + "/image_3/000000.png", image);
  return k;
}

// Frames of the dataset that get a pose from `camera` at the default run.pose_max_gap_s.
size_t framesWithoutPose(const StereoDataset& dataset, const io::Trajectory& camera) {
  size_t missing = 0;
  for (size_t i = 0; i < dataset.size(); ++i) missing += !camera.poseAt(dataset.timestamp(i), RunConfig{}.pose_max_gap_s);
  return missing;
}

TEST(KittiDataset, ExplicitPosesFileIsTimedAndPlacedExactlyAsTheDefaultLayout) {
  const KittiLike k = writeKittiLike("kitti_like");
  const auto dataset = openDataset(k.sequence);
  ASSERT_EQ(dataset->size(), 20u);
  // The colour camera (P2) sits 6 cm to the left of camera 0: -K^-1 P2(:, 3).
  EXPECT_NEAR(dataset->T_body_cam().translation().x(), -0.0599, 1e-4);
  const io::Trajectory by_default = cameraTrajectory(*dataset, "", "", PoseFrame::kAuto);
  const io::Trajectory explicit_kitti = cameraTrajectory(*dataset, k.poses, "kitti", PoseFrame::kAuto);
  const io::Trajectory detected = cameraTrajectory(*dataset, k.poses, "", PoseFrame::kAuto);
  EXPECT_EQ(framesWithoutPose(*dataset, by_default), 0u);
  EXPECT_EQ(framesWithoutPose(*dataset, explicit_kitti), 0u);
  EXPECT_EQ(framesWithoutPose(*dataset, detected), 0u);
  for (size_t i = 0; i < dataset->size(); ++i) {
    const double t = dataset->timestamp(i);
    const auto a = by_default.poseAt(t, RunConfig{}.pose_max_gap_s);
    const auto b = explicit_kitti.poseAt(t, RunConfig{}.pose_max_gap_s);
    ASSERT_TRUE(a && b) << "frame " << i << " (t = " << t << " s)";
    // The left (colour) camera: camera 0's pose at the frame's own time, composed with T_body_cam.
    const Eigen::Isometry3d expected = kittiCam0Pose(k.times[i]) * dataset->T_body_cam();
    EXPECT_NEAR((b->translation() - expected.translation()).norm(), 0.0, 1e-6) << "frame " << i;
    EXPECT_NEAR((b->translation() - a->translation()).norm(), 0.0, 1e-12) << "frame " << i;
  }
}

TEST(KittiDataset, TimesFileGivenForKittiPosesReplacesTheSequences) {
  const KittiLike k = writeKittiLike("kitti_times");
  const auto dataset = openDataset(k.sequence);
  const std::string shifted = k.root + "/shifted_times.txt";
  std::ofstream out(shifted);
  for (double t : k.times) out << t + 5.0 << "\n";
  out.close();
  const CameraTrajectory camera = loadCameraTrajectory(*dataset, {k.poses, "kitti", shifted, PoseFrame::kAuto});
  EXPECT_NEAR(camera.trajectory.poses().front().t_s, 5.0, 1e-12);
  EXPECT_EQ(framesWithoutPose(*dataset, camera.trajectory), 20u);
}

TEST(CameraTrajectory, KittiPosesWithoutTimesAreAnErrorOutsideAKittiSequence) {
  const std::string dir = freshEurocSequence("euroc_kitti_poses");
  const std::string poses = dir + "/poses.txt";
  std::ofstream(poses) << "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0.1 0 1 0 0 0 0 1 0\n";
  const auto dataset = openDataset(dir);
  try {
    loadCameraTrajectory(*dataset, {poses, "", "", PoseFrame::kAuto});
    FAIL() << "KITTI poses without times were timed anyway";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "trajectory " + poses +
                                         ": KITTI poses carry no timestamps and this dataset has no times.txt; give "
                                         "them with --trajectory-times FILE (one time a line, seconds)");
  }
  const std::string tum = dir + "/poses.tum";
  std::ofstream(tum) << "100 0 0 0 0 0 0 1\n101 0 0 0 0 0 0 1\n";
  try {
    loadCameraTrajectory(*dataset, {tum, "", dir + "/times.txt", PoseFrame::kAuto});
    FAIL() << "a times file was taken for TUM poses";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "trajectory times " + dir + "/times.txt: only KITTI poses take a times file; " + tum +
                                         " is tum, which carries its own timestamps");
  }
}

TEST(CameraTrajectory, TumPosesOnADatasetWithExtrinsicsSayWhichFrameWasAssumed) {
  const std::string dir = freshEurocSequence("euroc_tum");
  const std::string tum = dir + "/vio.tum";
  std::ofstream(tum) << "100 0 0 0 0 0 0 1\n101 0.15 0 0 0 0 0 1\n";
  const auto dataset = openDataset(dir);
  const CameraTrajectory assumed = loadCameraTrajectory(*dataset, {tum, "", "", PoseFrame::kAuto});
  EXPECT_TRUE(assumed.frame_assumed);
  EXPECT_STREQ(assumed.fileFrame(), "camera");
  EXPECT_EQ(assumed.note.rfind("poses of " + tum +
                                   " taken as camera poses: a tum file does not say which frame it "
                                   "describes, and the camera sits 0.050 m and 0.0 deg from the body of EuRoC ",
                               0),
            0u)
      << assumed.note;
  EXPECT_NE(assumed.note.find("; pass --pose-frame body if they are body (IMU) poses"), std::string::npos);
  EXPECT_NEAR(assumed.trajectory.poses()[0].T_world_cam.translation().x(), 0.0, 1e-12);
  // Saying which frame: nothing assumed, and body poses go through T_body_cam.
  const CameraTrajectory body = loadCameraTrajectory(*dataset, {tum, "", "", PoseFrame::kBody});
  EXPECT_FALSE(body.frame_assumed);
  EXPECT_TRUE(body.note.empty());
  EXPECT_NEAR(body.trajectory.poses()[0].T_world_cam.translation().x(), 0.05, 1e-12);
  EXPECT_FALSE(loadCameraTrajectory(*dataset, {tum, "", "", PoseFrame::kCamera}).frame_assumed);
  // EuRoC ground truth is body poses by its format: nothing assumed.
  EXPECT_FALSE(loadCameraTrajectory(*dataset, {}).frame_assumed);
  // The report carries it.
  RunReport report;
  report.pose_frame = assumed.fileFrame();
  report.pose_frame_assumed = assumed.frame_assumed;
  report.pose_frame_hint = assumed.note;
  const nlohmann::json j = nlohmann::json::parse(report.toJson());
  EXPECT_EQ(j["pose_frame"], "camera");
  EXPECT_EQ(j["pose_frame_assumed"], true);
  EXPECT_EQ(j["pose_frame_hint"], assumed.note);
}

TEST(CameraTrajectory, TumPosesOnAKittiGreySequenceAssumeNothing) {
  // Grey camera 0 is KITTI's reference: T_body_cam is the identity and the choice changes nothing.
  const std::string dir = freshDir("kitti_grey_tum");
  test::PlaneSequence s;
  test::writeKittiPlaneSequence(dir, s);
  const std::string tum = dir + "/vio.tum";
  std::ofstream(tum) << "0 0 0 0 0 0 0 1\n1 0.1 0 0 0 0 0 1\n";
  const auto dataset = openDataset(dir + "/sequences/00");
  EXPECT_FALSE(loadCameraTrajectory(*dataset, {tum, "", "", PoseFrame::kAuto}).frame_assumed);
}

}  // namespace
}  // namespace cenote::pipeline
