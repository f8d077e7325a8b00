// The parts of a recording dataset that need no recording: its configuration, and the stereo
// calibration recovered from the two cameras' CameraInfo as ROS's stereo calibration publishes it.
#include "pipeline/dataset/recording_dataset.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>

#include "common/error.h"

namespace cenote::pipeline {
namespace {

TEST(RecordingConfig, DefaultsAreValidAndBadValuesAreNamed) {
  EXPECT_TRUE(RecordingConfig{}.validate().empty());
  RecordingConfig bad;
  bad.sync_tolerance_s = -0.1;
  bad.sync_queue = 1;
  bad.image_bits = 8;
  bad.rig = "aqua";
  const std::vector<ConfigError> errors = bad.validate();
  ASSERT_EQ(errors.size(), 4u);
  EXPECT_EQ(errors[0].key, "bag.sync_tolerance_s");
  EXPECT_EQ(errors[1].key, "bag.sync_queue");
  EXPECT_EQ(errors[2].key, "bag.image_bits");
  EXPECT_EQ(errors[3].key, "bag.rig");
}

// The CameraInfo pair of a rig: K, D as calibrated; R, P from cv::stereoRectify (ROS's
// camera_calibration does the same).
std::pair<io::RosCameraInfo, io::RosCameraInfo> cameraInfos(const StereoCalibration& c) {
  cv::Mat R1, R2, P1, P2, Q;
  cv::stereoRectify(cv::Matx33d(c.left.K), c.left.distortion, cv::Matx33d(c.right.K), c.right.distortion, c.image_size, c.R,
                    c.T, R1, R2, P1, P2, Q, cv::CALIB_ZERO_DISPARITY, 0);
  auto info = [&](const CameraIntrinsics& cam, const cv::Mat& R, const cv::Mat& P) {
    io::RosCameraInfo m;
    m.width = static_cast<std::uint32_t>(c.image_size.width);
    m.height = static_cast<std::uint32_t>(c.image_size.height);
    m.distortion_model = "plumb_bob";
    m.D = cam.distortion;
    for (int i = 0; i < 9; ++i) m.K[i] = cam.K.val[i];
    for (int i = 0; i < 9; ++i) m.R[i] = R.at<double>(i / 3, i % 3);
    for (int i = 0; i < 12; ++i) m.P[i] = P.at<double>(i / 4, i % 4);
    return m;
  };
  return {info(c.left, R1, P1), info(c.right, R2, P2)};
}

TEST(CalibrationFromCameraInfo, RecoversTheRigsRotationAndBaseline) {
  StereoCalibration c;
  c.image_size = {752, 480};
  c.left.K = cv::Matx33d(458.6, 0, 367.2, 0, 457.3, 248.4, 0, 0, 1);
  c.left.distortion = {-0.28, 0.074, 0.0002, 0.00002, 0.0};
  c.right.K = cv::Matx33d(457.6, 0, 379.9, 0, 456.1, 255.2, 0, 0, 1);
  c.right.distortion = {-0.283, 0.0739, -0.0001, -0.00004, 0.0};
  cv::Rodrigues(cv::Vec3d(0.003, -0.012, 0.0021), c.R);
  c.T = cv::Vec3d(-0.1101, 0.0004, -0.0009);
  const auto [left, right] = cameraInfos(c);
  const StereoCalibration got = calibrationFromCameraInfo(left, right, "/l/camera_info", "/r/camera_info");
  EXPECT_EQ(got.image_size, c.image_size);
  EXPECT_LT(cv::norm(got.R - c.R), 1e-12);
  EXPECT_LT(cv::norm(got.T - c.T), 1e-12);
  EXPECT_EQ(got.left.distortion, c.left.distortion);
  EXPECT_EQ(cv::norm(got.right.K - c.right.K), 0.0);
}

TEST(CalibrationFromCameraInfo, NoBaselineOrAnUnreadModelIsAClearError) {
  io::RosCameraInfo left, right;
  left.width = right.width = 640;
  left.height = right.height = 480;
  left.K = right.K = {400, 0, 320, 0, 400, 240, 0, 0, 1};
  left.R = right.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  left.P = right.P = {400, 0, 320, 0, 0, 400, 240, 0, 0, 0, 1, 0};
  EXPECT_THAT([&] { calibrationFromCameraInfo(left, right, "/l/camera_info", "/r/camera_info"); },
              testing::ThrowsMessage<Error>("CameraInfo on /r/camera_info: P[3] is 0, so it carries no stereo baseline "
                                            "(the right camera's P[3] = -fx' * B); calibrate the pair as a stereo rig or "
                                            "give --calibration FILE"));
  right.P[3] = -40.0;
  left.distortion_model = "equidistant";
  left.D = {0.1, 0.0, 0.0, 0.0};
  EXPECT_THAT([&] { calibrationFromCameraInfo(left, right, "/l/camera_info", "/r/camera_info"); },
              testing::ThrowsMessage<Error>("CameraInfo on /l/camera_info: distortion model 'equidistant' is not read "
                                            "(plumb_bob or rational_polynomial); give --calibration FILE"));
  left.distortion_model = "plumb_bob";
  const StereoCalibration c = calibrationFromCameraInfo(left, right, "/l/camera_info", "/r/camera_info");
  EXPECT_NEAR(cv::norm(c.T), 0.1, 1e-15);  // B = -P[3] / fx' = 40 / 400
}

}  // namespace
}  // namespace cenote::pipeline
