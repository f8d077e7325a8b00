// The matcher's per-pixel image work (prefilterForSad, halveImage, disparityToDepth: SIMD rows in
// pipeline/stereo/matcher_kernels.cpp) against plain scalar forms of their rules, bit for bit, on
// every instruction set the machine runs and for widths that leave every possible tail.
#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "pipeline/stereo/stereo_matcher.h"

namespace cenote::pipeline {
namespace {

cv::Mat randomGrey(int width, int height, uint32_t seed) {
  cv::Mat m(height, width, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(m, cv::RNG::UNIFORM, 0, 256);
  return m;
}

// clamp(Sobel x, -cap, cap) + cap with OpenCV's derivative, pixel by pixel.
cv::Mat plainPrefilter(const cv::Mat& grey, int cap) {
  cv::Mat derivative;
  cv::Sobel(grey, derivative, CV_16S, 1, 0, 3, 1.0, 0.0, cv::BORDER_REPLICATE);
  cv::Mat out(grey.size(), CV_8UC1);
  for (int y = 0; y < grey.rows; ++y) {
    for (int x = 0; x < grey.cols; ++x) {
      out.at<uint8_t>(y, x) = static_cast<uint8_t>(std::clamp<int>(derivative.at<int16_t>(y, x), -cap, cap) + cap);
    }
  }
  return out;
}

// The rounded 2x2 mean, an odd last row or column averaged with itself.
cv::Mat plainHalf(const cv::Mat& grey) {
  cv::Mat half((grey.rows + 1) / 2, (grey.cols + 1) / 2, CV_8UC1);
  for (int y = 0; y < half.rows; ++y) {
    for (int x = 0; x < half.cols; ++x) {
      const int y1 = std::min(2 * y + 1, grey.rows - 1), x1 = std::min(2 * x + 1, grey.cols - 1);
      const int sum = grey.at<uint8_t>(2 * y, 2 * x) + grey.at<uint8_t>(2 * y, x1) + grey.at<uint8_t>(y1, 2 * x) +
                      grey.at<uint8_t>(y1, x1);
      half.at<uint8_t>(y, x) = static_cast<uint8_t>((sum + 2) / 4);
    }
  }
  return half;
}

bool sameBytes(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return false;
  for (int y = 0; y < a.rows; ++y) {
    if (std::memcmp(a.ptr(y), b.ptr(y), a.cols * a.elemSize()) != 0) return false;
  }
  return true;
}

TEST(MatcherKernels, EqualThePlainRulesOnEveryInstructionSet) {
  const float inf = std::numeric_limits<float>::infinity();
  const float special[] = {0.0f,   -0.0f,  -1.0f, inf,  -inf,   std::numeric_limits<float>::quiet_NaN(),
                           1e-40f, 1e-30f, 0.25f, 3.0f, 111.75f};
  for (const int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    for (int width = 1; width <= 140; width += 7) {
      const std::string where = std::string(hwy::TargetName(target)) + ", width " + std::to_string(width);
      for (int height : {1, 2, 5}) {
        const cv::Mat grey = randomGrey(width, height, static_cast<uint32_t>(width * 10 + height));
        for (int cap : {1, 31, 127}) {
          EXPECT_TRUE(sameBytes(prefilterForSad(grey, Prefilter::kSobelX, cap), plainPrefilter(grey, cap)))
              << where << ", cap " << cap;
        }
        cv::Mat half;
        halveImage(grey, half);
        EXPECT_TRUE(sameBytes(half, plainHalf(grey))) << where << ", height " << height;
      }
      cv::Mat disparity(2, width, CV_32FC1);
      cv::RNG rng(static_cast<uint64_t>(width));
      for (int x = 0; x < width; ++x) {
        disparity.at<float>(0, x) = special[x % std::size(special)];
        disparity.at<float>(1, x) = static_cast<float>(rng.uniform(-2.0, 120.0));
      }
      const float fb = static_cast<float>(480.0 * 0.12);
      cv::Mat expected(disparity.size(), CV_32FC1);
      for (int y = 0; y < 2; ++y) {
        for (int x = 0; x < width; ++x) {
          const float d = disparity.at<float>(y, x);
          expected.at<float>(y, x) = std::isfinite(d) && d > 0.0f ? fb / d : inf;
        }
      }
      EXPECT_TRUE(sameBytes(disparityToDepth(disparity, 480.0, 0.12), expected)) << where;
    }
  }
  hwy::SetSupportedTargetsForTest(0);
}

}  // namespace
}  // namespace cenote::pipeline
