#include "io/image/png_encoder.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "io/image/image_io.h"
#include "io/image/png_decoder.h"

namespace cenote::io {
namespace {

cv::Mat randomImage(int rows, int cols, int type, uint64_t seed) {
  cv::Mat image(rows, cols, type);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, CV_MAT_DEPTH(type) == CV_16U ? 65536 : 256);
  return image;
}

// A camera-like image: smooth gradients plus noise of a few grey levels.
cv::Mat noisyCameraImage(int rows, int cols, uint64_t seed) {
  cv::Mat image(rows, cols, CV_8UC3);
  cv::RNG rng(seed);
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) {
      for (int c = 0; c < 3; ++c) {
        const double value = 60 + 40 * std::sin(0.02 * x + c) * std::cos(0.03 * y) + rng.gaussian(2.0);
        image.ptr<uint8_t>(y)[3 * x + c] = cv::saturate_cast<uint8_t>(value);
      }
    }
  }
  return image;
}

void expectSamePixels(const cv::Mat& decoded, const cv::Mat& image, const std::string& what) {
  ASSERT_FALSE(decoded.empty()) << what << ": not decoded";
  ASSERT_EQ(decoded.type(), image.type()) << what;
  ASSERT_EQ(decoded.size(), image.size()) << what;
  EXPECT_EQ(cv::norm(decoded, image, cv::NORM_INF), 0.0) << what;
}

TEST(PngEncoder, RefusesWhatPngCannotHoldAsIs) {
  EXPECT_FALSE(isPngEncodable(cv::Mat()));
  EXPECT_FALSE(isPngEncodable(cv::Mat(4, 4, CV_32FC1)));
  EXPECT_FALSE(isPngEncodable(cv::Mat(4, 4, CV_16UC3)));
  EXPECT_FALSE(isPngEncodable(cv::Mat(4, 4, CV_8UC2)));
  EXPECT_TRUE(encodePng(cv::Mat(4, 4, CV_32FC1)).empty());
}

TEST(PngEncoder, OnePixelAndOneRowOrColumnImagesDecode) {
  for (const cv::Size size : {cv::Size(1, 1), cv::Size(17, 1), cv::Size(1, 13)}) {
    for (int type : {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1}) {
      const cv::Mat image = randomImage(size.height, size.width, type, 3 + type);
      const std::vector<uint8_t> png = encodePng(image);
      expectSamePixels(cv::imdecode(png, cv::IMREAD_UNCHANGED), image,
                       std::to_string(size.width) + "x" + std::to_string(size.height) + " type " + std::to_string(type));
    }
  }
}

TEST(PngEncoder, OpenCvAndOurDecoderReadBackTheSamePixels) {
  for (int type : {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1}) {
    const std::string what = "type " + std::to_string(type);
    const cv::Mat image = randomImage(61, 83, type, 100 + type);
    const std::vector<uint8_t> png = encodePng(image);
    expectSamePixels(cv::imdecode(png, cv::IMREAD_UNCHANGED), image, what + ", OpenCV");
    if (CV_MAT_DEPTH(type) == CV_8U) expectSamePixels(decodePngFast(png.data(), png.size()), image, what + ", ours");
  }
  // A view into a larger image (rows not contiguous), and flat areas (runs).
  const cv::Mat big = noisyCameraImage(120, 160, 4);
  const cv::Mat view = big(cv::Rect(7, 9, 101, 77));
  expectSamePixels(cv::imdecode(encodePng(view), cv::IMREAD_UNCHANGED), view, "view");
  cv::Mat holes = randomImage(90, 120, CV_16UC1, 8);
  holes(cv::Rect(10, 10, 80, 50)).setTo(0);
  expectSamePixels(cv::imdecode(encodePng(holes), cv::IMREAD_UNCHANGED), holes, "depth with holes");
}

TEST(PngEncoder, CameraImagesAreAboutTheSizeOfOpenCvsAndFlatImagesTiny) {
  const cv::Mat image = noisyCameraImage(240, 320, 1);
  std::vector<uint8_t> opencv;
  ASSERT_TRUE(cv::imencode(".png", image, opencv));
  const std::vector<uint8_t> ours = encodePng(image);
  EXPECT_LT(ours.size(), 1.03 * opencv.size()) << "ours " << ours.size() << " B, OpenCV " << opencv.size() << " B";
  expectSamePixels(cv::imdecode(ours, cv::IMREAD_UNCHANGED), image, "camera image (several deflate blocks), OpenCV");
  const cv::Mat black(600, 800, CV_8UC3, cv::Scalar::all(0));
  const std::vector<uint8_t> flat = encodePng(black);
  EXPECT_LT(flat.size(), 0.01 * black.total() * 3) << "a flat image is mostly runs";
  expectSamePixels(cv::imdecode(flat, cv::IMREAD_UNCHANGED), black, "flat image, OpenCV");
}

TEST(PngEncoder, WriteImageWritesAFileOpenCvReads) {
  const std::string path = testing::TempDir() + "/encoded.png";
  const cv::Mat image = noisyCameraImage(50, 70, 2);
  writeImage(path, image);
  expectSamePixels(cv::imread(path, cv::IMREAD_UNCHANGED), image, path);
  // Types our encoder refuses still go through OpenCV.
  const cv::Mat two_channels = randomImage(5, 6, CV_16UC3, 1);
  writeImage(path, two_channels);
  expectSamePixels(cv::imread(path, cv::IMREAD_UNCHANGED), two_channels, "16-bit colour via OpenCV");
}

}  // namespace
}  // namespace cenote::io
