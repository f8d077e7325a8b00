#include "pipeline/calibration/chessboard_calibration.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "common/error.h"
#include "pipeline/calibration/rectifier.h"
#include "io/image/image_io.h"

namespace cenote::pipeline {
namespace {

bool findCorners(const cv::Mat& grey, const cv::Size& board, std::vector<cv::Point2f>& corners) {
  if (!cv::findChessboardCorners(grey, board, corners, cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE)) {
    return false;
  }
  cv::cornerSubPix(grey, corners, cv::Size(11, 11), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.01));
  return true;
}

}  // namespace

ChessboardCalibration calibrateFromChessboards(const std::vector<std::pair<std::string, std::string>>& pairs,
                                               const ChessboardSpec& board) {
  if (board.inner_corners.width < 2 || board.inner_corners.height < 2 || !(board.square_m > 0.0)) {
    throw Error("calibrate: the board needs at least 2x2 inner corners and a positive square size");
  }
  ChessboardCalibration result;
  std::vector<std::vector<cv::Point2f>> left_points, right_points;
  cv::Size size;
  for (const auto& [left_file, right_file] : pairs) {
    const cv::Mat left = io::readImage(left_file, cv::IMREAD_GRAYSCALE);
    const cv::Mat right = io::readImage(right_file, cv::IMREAD_GRAYSCALE);
    if (size.empty()) size = left.size();
    if (left.size() != size || right.size() != size) {
      throw Error("calibrate: " + (left.size() != size ? left_file : right_file) + " is " +
                  std::to_string((left.size() != size ? left : right).cols) + "x" +
                  std::to_string((left.size() != size ? left : right).rows) + ", the first image is " +
                  std::to_string(size.width) + "x" + std::to_string(size.height));
    }
    std::vector<cv::Point2f> l, r;
    if (!findCorners(left, board.inner_corners, l)) {
      result.rejected.push_back(left_file + ": board not found");
      continue;
    }
    if (!findCorners(right, board.inner_corners, r)) {
      result.rejected.push_back(right_file + ": board not found");
      continue;
    }
    left_points.push_back(std::move(l));
    right_points.push_back(std::move(r));
  }
  result.pairs_used = static_cast<int>(left_points.size());
  if (result.pairs_used < 3) {
    throw Error("calibrate: the whole board was found in both images of only " + std::to_string(result.pairs_used) +
                " pair(s); at least 3 are needed");
  }
  std::vector<cv::Point3f> corners_board;
  for (int y = 0; y < board.inner_corners.height; ++y)
    for (int x = 0; x < board.inner_corners.width; ++x)
      corners_board.emplace_back(static_cast<float>(x * board.square_m), static_cast<float>(y * board.square_m), 0.0f);
  const std::vector<std::vector<cv::Point3f>> object_points(left_points.size(), corners_board);

  // Each camera alone first (a good start for the joint refinement), k3 fixed at 0.
  const int flags = cv::CALIB_FIX_K3;
  cv::Mat K1, D1, K2, D2, R, T, E, F;
  std::vector<cv::Mat> rvecs, tvecs;
  cv::calibrateCamera(object_points, left_points, size, K1, D1, rvecs, tvecs, flags);
  cv::calibrateCamera(object_points, right_points, size, K2, D2, rvecs, tvecs, flags);
  result.rms_px = cv::stereoCalibrate(object_points, left_points, right_points, K1, D1, K2, D2, size, R, T, E, F,
                                      cv::CALIB_USE_INTRINSIC_GUESS | flags,
                                      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-6));

  StereoCalibration& c = result.calibration;
  c.image_size = size;
  c.left.K = cv::Matx33d(K1);
  c.right.K = cv::Matx33d(K2);
  c.left.distortion.assign(D1.begin<double>(), D1.end<double>());
  c.right.distortion.assign(D2.begin<double>(), D2.end<double>());
  c.R = cv::Matx33d(R);
  c.T = cv::Vec3d(T.at<double>(0), T.at<double>(1), T.at<double>(2));
  result.rectified = Rectifier(c).geometry();
  return result;
}

}  // namespace cenote::pipeline
