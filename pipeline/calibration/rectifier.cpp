#include "pipeline/calibration/rectifier.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "common/error.h"

namespace cenote::pipeline {
namespace {

// Whether a CV_16SC2 + CV_16UC1 map pair (initUndistortRectifyMap's fixed-point form) sends every
// pixel to itself: integer part (x, y) and fractional table entry 0. cv::remap's bilinear weights
// for entry 0 are (1, 0, 0, 0) in fixed point, so it would return every pixel unchanged (the
// neighbours outside the image have weight 0): a copy, bit for bit.
bool isIdentityMap(const cv::Mat& map_xy, const cv::Mat& map_fraction) {
  for (int y = 0; y < map_xy.rows; ++y) {
    const int16_t* xy = map_xy.ptr<int16_t>(y);
    const uint16_t* fraction = map_fraction.ptr<uint16_t>(y);
    for (int x = 0; x < map_xy.cols; ++x) {
      if (xy[2 * x] != x || xy[2 * x + 1] != y || fraction[x] != 0) return false;
    }
  }
  return true;
}

}  // namespace

Rectifier::Rectifier(const StereoCalibration& c) : size_(c.image_size) {
  c.validate();
  if (c.rectified) {
    passthrough_ = true;
    geometry_ = c.rectified_geometry;
    return;
  }
  cv::Mat R1, R2, P1, P2, Q;
  cv::stereoRectify(cv::Mat(c.left.K), cv::Mat(c.left.distortion, true), cv::Mat(c.right.K),
                    cv::Mat(c.right.distortion, true), size_, cv::Mat(c.R), cv::Mat(c.T), R1, R2, P1, P2, Q,
                    cv::CALIB_ZERO_DISPARITY, 0.0, size_);
  cv::initUndistortRectifyMap(cv::Mat(c.left.K), cv::Mat(c.left.distortion, true), R1, P1, size_, CV_16SC2, map_left_x_,
                              map_left_y_);
  cv::initUndistortRectifyMap(cv::Mat(c.right.K), cv::Mat(c.right.distortion, true), R2, P2, size_, CV_16SC2, map_right_x_,
                              map_right_y_);
  // A rig that needs no resampling (no distortion, parallel cameras of equal K, as simulated)
  // gets exact identity maps: rectify() then hands the images on as it would a rectified rig's.
  identity_maps_ = isIdentityMap(map_left_x_, map_left_y_) && isIdentityMap(map_right_x_, map_right_y_);
  R_rect_left_ = cv::Matx33d(R1);
  geometry_.fx = P1.at<double>(0, 0);
  geometry_.fy = P1.at<double>(1, 1);
  geometry_.cx = P1.at<double>(0, 2);
  geometry_.cy = P1.at<double>(1, 2);
  // P2(0, 3) = -fx * baseline for a horizontal rig.
  geometry_.baseline_m = -P2.at<double>(0, 3) / P2.at<double>(0, 0);
  geometry_.image_size = size_;
  if (std::abs(P2.at<double>(1, 3)) > 1e-6 * std::abs(P2.at<double>(0, 3))) {
    throw Error("rectifier: the rig is vertical (baseline along y); only horizontal rigs are supported");
  }
}

RectifiedPair Rectifier::rectify(const StereoFrame& frame) const {
  for (const cv::Mat* image : {&frame.left, &frame.right}) {
    const char* which = image == &frame.left ? "left" : "right";
    if (image->empty()) throw Error(std::string("rectifier: ") + which + " image is empty");
    if (image->size() != size_) {
      throw Error(std::string("rectifier: ") + which + " image is " + std::to_string(image->cols) + "x" +
                  std::to_string(image->rows) + " but the calibration is for " + std::to_string(size_.width) + "x" +
                  std::to_string(size_.height));
    }
  }
  RectifiedPair pair;
  pair.t_s = frame.t_s;
  pair.geometry = geometry_;
  if (passthrough_ || identity_maps_) {
    pair.left = frame.left;
    pair.right = frame.right;
    return pair;
  }
  cv::remap(frame.left, pair.left, map_left_x_, map_left_y_, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  cv::remap(frame.right, pair.right, map_right_x_, map_right_y_, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  return pair;
}

}  // namespace cenote::pipeline
