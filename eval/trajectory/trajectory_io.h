// trajectory_io.h: trajectories for evaluation, in the formats users compare against.
//   tum     `t tx ty tz qx qy qz qw`                       (io/trajectory/trajectory.h)
//   euroc   CSV `t_ns, px, py, pz, qw, qx, qy, qz[, ...]`  (io/trajectory/trajectory.h)
//   kitti   12 numbers a line, row-major [R | t]; times from a file, else the line index at 10 Hz
//   colmap  sparse model images.txt: `IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME` then a line of
//           2-D points; the pose is T_cam_world (world to camera), inverted here. The timestamp is
//           the image name without extension ("1403636579.763555.png" -> 1403636579.763555).
// Every pose is returned as T_world_cam (camera centre = translation), in time order.
// Threads: free functions, independent.
#pragma once

#include <string>
#include <vector>

#include "io/trajectory/tum_trajectory.h"

namespace cenote::eval {

enum class TrajectoryFileFormat { kAuto, kTum, kEuroc, kKitti, kColmap, kOkvis };

// "auto", "tum", "euroc", "kitti", "colmap" or "okvis" (OKVIS / SVIn2 CSV). @throws cenote::Error otherwise.
TrajectoryFileFormat parseTrajectoryFileFormat(const std::string& name);
const char* toString(TrajectoryFileFormat format);

// kAuto: images.txt or a COLMAP image line -> colmap, commas -> euroc, 8 numbers -> tum, 12 -> kitti.
// @throws cenote::Error naming the file when it is missing or fits no format.
TrajectoryFileFormat detectTrajectoryFileFormat(const std::string& path);

// @param kitti_times KITTI only: file of one timestamp (s) per line; empty = line index at 10 Hz.
// @throws cenote::Error naming the file and line of the first malformed entry, or when the file
//         holds no pose.
std::vector<io::StampedPose> readTrajectoryFile(const std::string& path, TrajectoryFileFormat format,
                                                const std::string& kitti_times = "");

// COLMAP images.txt. @throws cenote::Error naming file and line (bad numbers, a quaternion whose
//         norm is not 1, an image name that is not a timestamp, two images at one time).
std::vector<io::StampedPose> readColmapImagesTxt(const std::string& path);

}  // namespace cenote::eval
