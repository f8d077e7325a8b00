#include "pipeline/calibration/chessboard_calibration.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "common/error.h"
#include "pipeline/calibration/rectifier.h"
#include "tests/support/test_data.h"

namespace cenote::pipeline {
namespace {
namespace fs = std::filesystem;

std::vector<std::pair<std::string, std::string>> chessboardPairs() {
  std::vector<std::pair<std::string, std::string>> pairs;
  const std::string dir = test::fetchedDataDir() + "/chessboard/";
  for (int i = 1; i <= 14; ++i) {
    char l[32], r[32];
    std::snprintf(l, sizeof(l), "left%02d.jpg", i);
    std::snprintf(r, sizeof(r), "right%02d.jpg", i);
    if (fs::exists(dir + l) && fs::exists(dir + r)) pairs.emplace_back(dir + l, dir + r);
  }
  return pairs;
}

// OpenCV's own stereo sample pairs (Debian opencv-doc), a 9x6 board.
TEST(ChessboardCalibration, RealPairsGiveSubPixelErrorAndRectifiedCornersShareRows) {
  const auto pairs = chessboardPairs();
  if (pairs.size() < 10) GTEST_SKIP() << "chessboard pairs absent (scripts/fetch-test-data.sh)";
  ChessboardSpec board;
  board.square_m = 0.025;
  const ChessboardCalibration result = calibrateFromChessboards(pairs, board);
  std::cout << "pairs " << result.pairs_used << ", rms " << result.rms_px << " px, rectified f " << result.rectified.fx
            << " px, baseline " << result.rectified.baseline_m << " m\n";
  EXPECT_EQ(result.pairs_used, static_cast<int>(pairs.size()));
  EXPECT_LT(result.rms_px, 0.6);
  EXPECT_GT(result.rectified.baseline_m, 0.0);
  // After rectification, a corner has the same row in both images.
  const Rectifier rectifier(result.calibration);
  StereoFrame frame;
  frame.left = cv::imread(pairs[0].first, cv::IMREAD_GRAYSCALE);
  frame.right = cv::imread(pairs[0].second, cv::IMREAD_GRAYSCALE);
  const RectifiedPair pair = rectifier.rectify(frame);
  std::vector<cv::Point2f> l, r;
  ASSERT_TRUE(cv::findChessboardCorners(pair.left, board.inner_corners, l));
  ASSERT_TRUE(cv::findChessboardCorners(pair.right, board.inner_corners, r));
  double worst = 0.0;
  for (size_t i = 0; i < l.size(); ++i) worst = std::max(worst, std::abs(double(l[i].y - r[i].y)));
  EXPECT_LT(worst, 1.5) << "largest row difference of a corner, px";
}

TEST(ChessboardCalibration, TooFewBoardsIsAnError) {
  const auto pairs = chessboardPairs();
  if (pairs.size() < 2) GTEST_SKIP() << "chessboard pairs absent";
  EXPECT_THROW(calibrateFromChessboards({pairs[0], pairs[1]}, ChessboardSpec{}), Error);
  ChessboardSpec wrong;
  wrong.inner_corners = cv::Size(7, 7);  // not the board in these images
  EXPECT_THROW(calibrateFromChessboards(pairs, wrong), Error);
}

}  // namespace
}  // namespace cenote::pipeline
