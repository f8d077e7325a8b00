// plane_sequence.h: a tiny recorded stereo sequence with exact geometry, written to disk in the
// EuRoC or KITTI layout for reader and runner tests. The rig looks along world +z at a textured
// plane z = depth_m and slides along world x; every pixel's disparity is f b / depth.
#pragma once

#include <string>

namespace cenote::test {

struct PlaneSequence {
  int width = 160, height = 120, frames = 9;
  double fx = 300.0, baseline_m = 0.1, depth_m = 2.0;
  double speed_m_s = 0.15, rate_hz = 15.0;
  double t0_s = 100.0;
  double body_offset_x_m = 0.05;  // camera 0 sits here in the body frame (EuRoC T_BS)
};

// Writes <dir>/mav0/{cam0,cam1}/{data.csv,data/*.png,sensor.yaml} and
// <dir>/mav0/state_groundtruth_estimate0/data.csv (body poses at 200 Hz covering the images).
void writeEurocPlaneSequence(const std::string& dir, const PlaneSequence& s);

// Writes <dir>/sequences/00/{image_0,image_1,calib.txt,times.txt} and <dir>/poses/00.txt.
void writeKittiPlaneSequence(const std::string& dir, const PlaneSequence& s);

}  // namespace cenote::test
