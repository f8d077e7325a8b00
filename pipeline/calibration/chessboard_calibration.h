// chessboard_calibration.h: stereo calibration from pairs of chessboard images (OpenCV's
// findChessboardCorners + stereoCalibrate), for `cenote calibrate`.
//
// Calibrate in water, through the same housing ports the rig dives with: refraction at a flat
// port changes the focal length by about the refractive index of water (x1.33) and adds radial
// distortion, so an in-air calibration does not hold underwater.
//
// Units: the board's square size sets the unit of T (metres when square_m is in metres); pixels.
// Model: pinhole with radial-tangential distortion (k1, k2, p1, p2, k3 = 0).
// Threads: pure function; uses OpenCV's threads inside.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "pipeline/calibration/stereo_calibration.h"

namespace cenote::pipeline {

struct ChessboardSpec {
  cv::Size inner_corners{9, 6};  // corners where four squares meet, along x and y
  double square_m = 0.025;       // side of one square
};

struct ChessboardCalibration {
  StereoCalibration calibration;
  double rms_px = 0.0;  // stereo reprojection error over every corner of every pair used
  int pairs_used = 0;
  std::vector<std::string> rejected;  // "<left file>: board not found in the right image", ...
  StereoGeometry rectified;           // focal length and baseline after rectification
};

// @param pairs (left file, right file) of each view.
// @throws cenote::Error when an image is unreadable, sizes differ, or fewer than 3 pairs show the
//         whole board in both images.
ChessboardCalibration calibrateFromChessboards(const std::vector<std::pair<std::string, std::string>>& pairs,
                                               const ChessboardSpec& board);

}  // namespace cenote::pipeline
