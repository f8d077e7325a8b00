#include "tests/support/test_data.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "io/image/image_io.h"

namespace cenote::test {
namespace fs = std::filesystem;

std::string sharedDataDir() {
  if (const char* env = std::getenv("CENOTE_SHARED_DATA")) return env;
  return std::string(CENOTE_SOURCE_DIR) + "/../shared/data";
}

std::string fetchedDataDir() {
  if (const char* env = std::getenv("CENOTE_DATA")) return env;
  return std::string(CENOTE_SOURCE_DIR) + "/data";
}

namespace {

bool allExist(std::initializer_list<std::string> paths) {
  for (const auto& p : paths) {
    if (!fs::exists(p)) return false;
  }
  return true;
}

// 8-bit ground truth: value / scale, 0 = unknown.
cv::Mat truthFromPng(const std::string& path, float scale) {
  cv::Mat raw = cv::imread(path, cv::IMREAD_GRAYSCALE);
  cv::Mat truth(raw.size(), CV_32F);
  for (int y = 0; y < raw.rows; ++y) {
    for (int x = 0; x < raw.cols; ++x) {
      const uint8_t v = raw.at<uint8_t>(y, x);
      truth.at<float>(y, x) = v == 0 ? NAN : v / scale;
    }
  }
  return truth;
}

// Evaluate where the truth is known and its match x - d lies inside the right image.
cv::Mat maskFromTruth(const cv::Mat& truth) {
  cv::Mat mask(truth.size(), CV_8U, cv::Scalar(0));
  for (int y = 0; y < truth.rows; ++y) {
    for (int x = 0; x < truth.cols; ++x) {
      const float d = truth.at<float>(y, x);
      if (std::isfinite(d) && x - d >= 0.0f) mask.at<uint8_t>(y, x) = 255;
    }
  }
  return mask;
}

// A pair whose 8-bit ground truth is disparity * truth_scale (0 = unknown), evaluated wherever it
// is known and matchable.
std::optional<StereoPairWithTruth> loadPairWithPngTruth(const std::string& dir, const std::string& name,
                                                        const std::string& left, const std::string& right,
                                                        const std::string& truth, float truth_scale, int num_disparities) {
  if (!allExist({dir + left, dir + right, dir + truth})) return std::nullopt;
  StereoPairWithTruth p;
  p.name = name;
  p.left = cv::imread(dir + left, cv::IMREAD_COLOR);
  p.right = cv::imread(dir + right, cv::IMREAD_COLOR);
  p.truth = truthFromPng(dir + truth, truth_scale);
  p.mask = maskFromTruth(p.truth);
  p.num_disparities = num_disparities;
  return p;
}

}  // namespace

std::optional<StereoPairWithTruth> loadCones() {
  const std::string dir = sharedDataDir() + "/middlebury/cones/";
  if (!allExist({dir + "im2.png", dir + "im6.png", dir + "disp2.png", dir + "cones_mask.png"})) return std::nullopt;
  StereoPairWithTruth p;
  p.name = "cones";
  p.left = cv::imread(dir + "im2.png", cv::IMREAD_COLOR);
  p.right = cv::imread(dir + "im6.png", cv::IMREAD_COLOR);
  p.truth = truthFromPng(dir + "disp2.png", 4.0f);
  p.mask = cv::imread(dir + "cones_mask.png", cv::IMREAD_GRAYSCALE);
  p.mask = (p.mask > 0) & (maskFromTruth(p.truth) > 0);
  p.num_disparities = 64;
  return p;
}

std::optional<StereoPairWithTruth> loadCloth3() {
  return loadPairWithPngTruth(sharedDataDir() + "/middlebury/Cloth3/", "Cloth3", "view1.png", "view5.png", "disp1.png",
                              2.0f, 128);
}

std::optional<StereoPairWithTruth> loadMotorcycle() {
  const std::string dir = fetchedDataDir() + "/motorcycle/";
  if (!allExist({dir + "motorcycle_left.png", dir + "motorcycle_right.png", dir + "motorcycle_disp.pfm"})) {
    return std::nullopt;
  }
  StereoPairWithTruth p;
  p.name = "Motorcycle";
  p.left = cv::imread(dir + "motorcycle_left.png", cv::IMREAD_COLOR);
  p.right = cv::imread(dir + "motorcycle_right.png", cv::IMREAD_COLOR);
  p.truth = io::readPfm(dir + "motorcycle_disp.pfm");
  for (int y = 0; y < p.truth.rows; ++y) {
    for (int x = 0; x < p.truth.cols; ++x) {
      float& d = p.truth.at<float>(y, x);
      if (!std::isfinite(d) || d <= 0.0f) d = NAN;
    }
  }
  p.mask = maskFromTruth(p.truth);
  // Largest true disparity of the quarter-size pair is 60 px.
  p.num_disparities = 64;
  return p;
}

// OpenCV's copy of Middlebury 2006 Aloe: full size, ground truth in pixels; the largest is 211.
std::optional<StereoPairWithTruth> loadAloe() {
  return loadPairWithPngTruth(fetchedDataDir() + "/aloe/", "Aloe", "aloeL.jpg", "aloeR.jpg", "aloeGT.png", 1.0f, 224);
}

BadPixelStats badPixels(const cv::Mat& disparity, const StereoPairWithTruth& pair) {
  BadPixelStats s;
  int bad1 = 0, bad2 = 0, dense = 0;
  for (int y = 0; y < disparity.rows; ++y) {
    for (int x = 0; x < disparity.cols; ++x) {
      if (pair.mask.at<uint8_t>(y, x) == 0) continue;
      ++s.evaluated;
      const float d = disparity.at<float>(y, x);
      if (!std::isfinite(d)) {
        ++bad1;
        ++bad2;
        continue;
      }
      ++dense;
      const float e = std::abs(d - pair.truth.at<float>(y, x));
      bad1 += e > 1.0f;
      bad2 += e > 2.0f;
    }
  }
  const double n = std::max(1, s.evaluated);
  s.bad1 = 100.0 * bad1 / n;
  s.bad2 = 100.0 * bad2 / n;
  s.density = 100.0 * dense / n;
  return s;
}

}  // namespace cenote::test
