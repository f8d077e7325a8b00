// host_viewer_test.cpp: the camera images cenote-server makes for the viewer from a fused frame:
// the left image and the disparity preview, scaled to the configured width, JPEG.
#include "server/viewer/host_viewer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace cenote::server {
namespace {

// An 800x600 frame: a horizontal grey ramp, depth 2 m on the left half, none on the right.
pipeline::DepthFrame rampFrame() {
  pipeline::DepthFrame frame;
  frame.t_s = 4.0;
  frame.color.create(600, 800, CV_8UC3);
  for (int u = 0; u < 800; ++u) frame.color.col(u).setTo(cv::Scalar::all(u * 255 / 799));
  frame.depth = cv::Mat(600, 800, CV_32FC1, cv::Scalar(INFINITY));
  frame.depth.colRange(0, 400).setTo(2.0f);
  frame.K << 500.0, 0.0, 400.0, 0.0, 500.0, 300.0, 0.0, 0.0, 1.0;
  return frame;
}

cv::Mat decoded(const std::string& jpeg) {
  return cv::imdecode(cv::Mat(1, static_cast<int>(jpeg.size()), CV_8UC1, const_cast<char*>(jpeg.data())), cv::IMREAD_COLOR);
}

TEST(CameraImages, AreTheLeftImageAndItsDisparityScaledToTheWidth) {
  viewer::LiveFeed live(100, 10, 1.0);
  live.setWanted(false, true);
  pipeline::StereoConfig stereo;
  stereo.min_disparity_px = 0;
  stereo.num_disparities = 128;
  postCameraImages(live, rampFrame(), 0.1, stereo, 640);  // fx * b / z = 500 * 0.1 / 2 = 25 px

  const viewer::LiveFeed::Images images = live.images();
  ASSERT_EQ(images.version, 1u);
  EXPECT_EQ(images.t_s, 4.0);
  const cv::Mat left = decoded(*images.left_jpeg);
  const cv::Mat preview = decoded(*images.disparity_jpeg);
  ASSERT_EQ(left.size(), cv::Size(640, 480));
  ASSERT_EQ(preview.size(), cv::Size(640, 480));
  // The ramp survives scaling and JPEG within a few grey levels.
  EXPECT_NEAR(left.at<cv::Vec3b>(240, 320)[1], 127.0, 4.0);
  EXPECT_NEAR(left.at<cv::Vec3b>(240, 600)[1], 600.0 / 639.0 * 255.0, 4.0);
  // Left half: turbo's colour of 25 px in [0, 128); right half: black (no depth).
  cv::Mat index(1, 1, CV_8UC1, cv::Scalar(static_cast<double>(std::lround(25.0 * 255.0 / 128.0)))), turbo;
  cv::applyColorMap(index, turbo, cv::COLORMAP_TURBO);
  const cv::Vec3b expected = turbo.at<cv::Vec3b>(0, 0), shown = preview.at<cv::Vec3b>(240, 150);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(shown[c], expected[c], 6.0) << "channel " << c;
  const cv::Vec3b none = preview.at<cv::Vec3b>(240, 500);
  EXPECT_LE(none[0] + none[1] + none[2], 12);
}

TEST(CameraImages, AreNotMadeWhenNotDueOrWithoutMaps) {
  pipeline::StereoConfig stereo;
  viewer::LiveFeed live(100, 10, 1.0);
  postCameraImages(live, rampFrame(), 0.1, stereo, 640);  // nobody wants them
  EXPECT_EQ(live.images().version, 0u);
  live.setWanted(false, true);
  pipeline::DepthFrame without_maps;  // an output whose maps were not kept
  postCameraImages(live, without_maps, 0.1, stereo, 640);
  EXPECT_EQ(live.images().version, 0u);
  postCameraImages(live, rampFrame(), 0.1, stereo, 1000);  // narrower than the width: kept as it is
  ASSERT_EQ(live.images().version, 1u);
  EXPECT_EQ(decoded(*live.images().left_jpeg).size(), cv::Size(800, 600));
}

}  // namespace
}  // namespace cenote::server
