// depth_frame.h: a depth image with its pinhole intrinsics and camera pose, the input of projective
// integration (OccupancyMap::integrateDepth, integration/projective_batch.h).
// Units: metres (depth along the optical axis, z), pixels (intrinsics). Frames: camera (x right,
// y down, z forward) and world; T_world_cam maps camera points to world points.
// Pixel (u, v) covers [u - 0.5, u + 0.5) x [v - 0.5, v + 0.5); its centre's ray is
// ((u - cx) / fx, (v - cy) / fy, 1).
// Why not pipeline/frame/frames.h's DepthFrame: mapping/ links no OpenCV (that one holds cv::Mat
// images and stereo confidence); this is the map's own, plain-vector input, filled by whoever
// holds a depth image (an RGB-D camera, a stored frame re-integrated with a corrected pose).
// Threads: a plain value.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <vector>

namespace cenote::mapping {

struct DepthFrame {
  double t_s = 0.0;
  int width = 0;
  int height = 0;
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;  // pixels; fx, fy > 0
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  std::vector<float> depth_m;                  // width * height, row-major; <= 0 or non-finite: no depth
  std::vector<std::array<uint8_t, 3>> colors;  // RGB per pixel, or empty

  bool hasColor() const { return !colors.empty(); }
};

}  // namespace cenote::mapping
