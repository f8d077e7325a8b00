// correction_events.h: loop-closure corrections as `cenote run --corrections PATH` replays them.
// A folder holds one TUM file per correction event, named by the time the correction became known,
// in seconds of the dataset's clock (`1700000042.500000.tum`; `cenote sim --drift` writes them):
// the corrected poses of past frames, in the frame the run's --trajectory describes (its
// --pose-frame). A file is SVIn2's pose-graph output (pose_graph's LoopClosing writes
// `svin_results/svin_<date>.txt`): a row `t x y z qx qy qz qw` per keyframe (t in seconds, fixed
// 9 decimals; the keyframe's pose T_WS of the IMU in the loop-closed world), appended per keyframe
// and rewritten whole after each pose-graph optimisation, so it holds only the latest correction:
// one event, known at its last keyframe's time. Each event is applied when the run reaches its
// time (apps/cenote/run_command.cpp).
// Units: seconds, metres. Threads: plain values.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "io/trajectory/trajectory.h"

namespace cenote::pipeline {

struct CorrectionEvent {
  double t_s = 0.0;      // when the correction became known
  std::string path;      // its file
  io::Trajectory poses;  // corrected T_world_cam of the raw left camera
};

// The events of `path` (a folder of TUM files or an SVIn2 pose-graph file), in time order; body
// poses (file_describes_body for a folder, always for SVIn2's file) are composed with T_body_cam,
// as the run's trajectory is.
// @throws NotFoundError for a missing path; Error naming the file for a .tum file whose name is
//   not a time in seconds, a malformed file (io::Trajectory::read), two events at one time, a
//   folder without any .tum file, or an SVIn2 file without a keyframe.
std::vector<CorrectionEvent> readCorrectionEvents(const std::string& path, bool file_describes_body,
                                                  const Eigen::Isometry3d& T_body_cam);

// SVIn2's pose-graph file as one event at its last keyframe's time, its IMU poses composed with
// T_body_cam. @throws Error naming the file when it is malformed or holds no keyframe.
CorrectionEvent readSvinLoopPath(const std::string& path, const Eigen::Isometry3d& T_body_cam);

}  // namespace cenote::pipeline
