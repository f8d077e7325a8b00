// correction_events.h: loop-closure corrections as `cenote run --corrections DIR` replays them.
// DIR holds one TUM file per correction event, named by the time the correction became known, in
// seconds of the dataset's clock (`1700000042.500000.tum`; `cenote sim --drift` writes them):
// the corrected poses of past frames, in the frame the run's --trajectory describes (its
// --pose-frame). Each event is applied when the run reaches its time (apps/cenote/run_command.cpp).
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

// The events of `dir`, in time order; body poses (file_describes_body) are composed with
// T_body_cam, as the run's trajectory is.
// @throws NotFoundError for a missing folder; Error naming the file for a .tum file whose name is
//   not a time in seconds, a malformed file (io::Trajectory::read), two events at one time, or a
//   folder without any .tum file.
std::vector<CorrectionEvent> readCorrectionEvents(const std::string& dir, bool file_describes_body,
                                                  const Eigen::Isometry3d& T_body_cam);

}  // namespace cenote::pipeline
