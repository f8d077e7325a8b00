// Tests of the 16-bit depth PNG functions of io/image/image_io.h.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "common/error.h"
#include "io/image/image_io.h"

namespace cenote::io {
namespace {

TEST(DepthPng16, RoundTripsToTheMillimetreWithNoneAsZero) {
  cv::Mat depth(2, 3, CV_32F);
  depth.at<float>(0, 0) = 1.2344f;  // -> 1234 mm
  depth.at<float>(0, 1) = 1.2346f;  // -> 1235 mm
  depth.at<float>(0, 2) = std::numeric_limits<float>::infinity();
  depth.at<float>(1, 0) = 0.0f;
  depth.at<float>(1, 1) = NAN;
  depth.at<float>(1, 2) = 70.0f;  // does not fit in 16 bits of millimetres
  const std::string path = (std::filesystem::temp_directory_path() / "cenote_depth16_test.png").string();
  EXPECT_EQ(writeDepthPng16(path, depth), 1);
  const cv::Mat raw = cv::imread(path, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(raw.type(), CV_16UC1);
  EXPECT_EQ(raw.at<uint16_t>(0, 0), 1234);
  EXPECT_EQ(raw.at<uint16_t>(0, 1), 1235);
  EXPECT_EQ(raw.at<uint16_t>(0, 2), 0);
  EXPECT_EQ(raw.at<uint16_t>(1, 2), 0);
  const cv::Mat back = readDepthPng16(path);
  EXPECT_FLOAT_EQ(back.at<float>(0, 0), 1.234f);
  EXPECT_TRUE(std::isinf(back.at<float>(1, 0)));
  std::filesystem::remove(path);
}

TEST(DepthPng16, RejectsNonFloatInputAndEightBitFiles) {
  const std::string path = (std::filesystem::temp_directory_path() / "cenote_depth8_test.png").string();
  EXPECT_THROW(writeDepthPng16(path, cv::Mat(2, 2, CV_8U)), Error);
  writeImage(path, cv::Mat(2, 2, CV_8U, cv::Scalar(3)));
  EXPECT_THROW(readDepthPng16(path), Error);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace cenote::io
