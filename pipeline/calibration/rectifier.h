// rectifier.h: turns raw stereo pairs into rectified ones, with maps computed once.
// cv::stereoRectify (zero disparity at infinity, alpha 0: only valid pixels) and
// cv::initUndistortRectifyMap at construction; rectify() is then one cv::remap per image.
// An already rectified calibration passes images through untouched, and so does a raw rig whose
// maps are exactly the identity (what cv::remap would return is then the input, bit for bit).
// Threads: rectify() is const and may be called from several threads at once.
#pragma once

#include "pipeline/calibration/stereo_calibration.h"
#include "pipeline/frame/frames.h"

namespace cenote::pipeline {

class Rectifier {
 public:
  // @throws cenote::Error when the calibration is invalid.
  explicit Rectifier(const StereoCalibration& calibration);

  // @throws cenote::Error when either image is empty or not of the calibrated size.
  RectifiedPair rectify(const StereoFrame& frame) const;

  const StereoGeometry& geometry() const { return geometry_; }
  bool isPassthrough() const { return passthrough_; }
  // Whether rectify() hands the images on unchanged: passthrough, or identity maps.
  bool keepsImages() const { return passthrough_ || identity_maps_; }
  // Rotation from the raw left camera to the rectified left camera (identity for passthrough).
  const cv::Matx33d& R_rect_left() const { return R_rect_left_; }

 private:
  StereoGeometry geometry_;
  cv::Size size_;
  bool passthrough_ = false;
  bool identity_maps_ = false;  // a raw rig whose maps send every pixel to itself
  cv::Matx33d R_rect_left_ = cv::Matx33d::eye();
  cv::Mat map_left_x_, map_left_y_, map_right_x_, map_right_y_;
};

}  // namespace cenote::pipeline
