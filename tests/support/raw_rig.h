// raw_rig.h: a raw (unrectified) stereo rig from its numbers, for calibration, rectification and
// frame-admission tests that each want a distorted, slightly rotated rig of their own.
#pragma once

#include <opencv2/calib3d.hpp>
#include <vector>

#include "pipeline/calibration/stereo_calibration.h"

namespace cenote::test {

// One camera's 3x3 intrinsics and radial-tangential distortion (k1, k2, p1, p2[, k3]).
struct RawCamera {
  cv::Matx33d K;
  std::vector<double> distortion;
};

// The rig of `left` and `right` on images of `size`, with the left-to-right rotation given as a
// Rodrigues vector `rotation` (radians) and the translation `T` in metres (stereo_calibration.h).
inline pipeline::StereoCalibration rawRig(cv::Size size, const RawCamera& left, const RawCamera& right,
                                          const cv::Vec3d& rotation, const cv::Vec3d& T) {
  pipeline::StereoCalibration c;
  c.image_size = size;
  c.left.K = left.K;
  c.left.distortion = left.distortion;
  c.right.K = right.K;
  c.right.distortion = right.distortion;
  cv::Mat R;
  cv::Rodrigues(rotation, R);
  c.R = cv::Matx33d(R);
  c.T = T;
  return c;
}

}  // namespace cenote::test
