// depth_index.h: the index of the depth maps `cenote run --write-depth` writes, OUT/depth/frames.csv,
// one row per map written, so that `cenote fuse` (or anyone) can read the maps with their camera:
//   name,t_s,fx,fy,cx,cy,r00,r01,r02,tx,r10,r11,r12,ty,r20,r21,r22,tz
// `name` is the file stem (<name>.depth.pfm, .conf.pfm, .jpg beside it), t_s the frame's time in
// seconds, fx fy cx cy the rectified left camera's pinhole intrinsics in pixels and the rest
// T_world_cam of that camera (rotation rows and translation in metres), every number printed with 17
// significant digits so that it reads back to the same double.
// Threads: a DepthIndexWriter is used by one thread.
#pragma once

#include <Eigen/Geometry>
#include <fstream>
#include <string>
#include <vector>

namespace cenote::pipeline {

struct DepthIndexRow {
  std::string name;
  double t_s = 0.0;
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
};

class DepthIndexWriter {
 public:
  /// Creates (truncates) `path` with its header line. @throws Error naming the file when it cannot.
  explicit DepthIndexWriter(const std::string& path);
  /// @throws Error naming the file when the row cannot be written (a full disk).
  void add(const DepthIndexRow& row);

 private:
  std::string path_;
  std::ofstream out_;
};

/// The rows of a frames.csv. @throws Error naming the file and line for a missing file, a row without
/// 18 fields or a field that is not a number.
std::vector<DepthIndexRow> readDepthIndex(const std::string& path);

}  // namespace cenote::pipeline
