// test_data.h: where the tests find real data, and loaders for the Middlebury pairs.
//   ../shared/data/middlebury/{cones,Cloth3}      beside the project (CENOTE_SHARED_DATA overrides)
//   data/{motorcycle,aloe,chessboard}             unpacked from Debian packages by
//                                                 scripts/fetch-test-data.sh (CENOTE_DATA overrides)
// A test whose data is absent calls GTEST_SKIP() with the path it looked for.
#pragma once

#include <opencv2/core.hpp>
#include <optional>
#include <string>

namespace cenote::test {

std::string sharedDataDir();   // may not exist
std::string fetchedDataDir();  // may not exist

// A rectified pair with ground-truth disparity of the left view (+inf or 0 = unknown -> NaN here)
// and an evaluation mask (255 = evaluate).
struct StereoPairWithTruth {
  std::string name;
  cv::Mat left, right;  // BGR
  cv::Mat truth;        // CV_32F disparity, NaN = unknown
  cv::Mat mask;         // CV_8U
  int num_disparities = 0;
};

std::optional<StereoPairWithTruth> loadCones();
std::optional<StereoPairWithTruth> loadCloth3();
std::optional<StereoPairWithTruth> loadMotorcycle();
std::optional<StereoPairWithTruth> loadAloe();

struct BadPixelStats {
  double bad1 = 0.0;  // % of evaluated pixels with |error| > 1 (invalid counts as bad)
  double bad2 = 0.0;
  double density = 0.0;  // % of evaluated pixels with an estimate
  int evaluated = 0;
};

// @param disparity CV_32F, non-finite = invalid.
BadPixelStats badPixels(const cv::Mat& disparity, const StereoPairWithTruth& pair);

}  // namespace cenote::test
