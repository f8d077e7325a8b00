#include "pipeline/runner/correction_events.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "common/error.h"

namespace cenote::pipeline {

CorrectionEvent readSvinLoopPath(const std::string& path, const Eigen::Isometry3d& T_body_cam) {
  // SVIn2's rows are TUM's layout; its poses are the IMU's whatever the run's --pose-frame says.
  const io::Trajectory poses = io::Trajectory::read(path, io::TrajectoryFormat::kTum);
  if (poses.empty()) throw Error("corrections " + path + ": no keyframe in SVIn2's pose-graph file");
  CorrectionEvent event;
  event.t_s = poses.poses().back().t_s;
  event.path = path;
  event.poses = poses.transformedBy(T_body_cam);
  return event;
}

std::vector<CorrectionEvent> readCorrectionEvents(const std::string& dir, bool file_describes_body,
                                                  const Eigen::Isometry3d& T_body_cam) {
  namespace fs = std::filesystem;
  if (fs::is_regular_file(dir)) return {readSvinLoopPath(dir, T_body_cam)};
  if (!fs::is_directory(dir)) throw NotFoundError("corrections " + dir + ": no such folder or file");
  std::vector<CorrectionEvent> events;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (!entry.is_regular_file() || entry.path().extension() != ".tum") continue;
    const std::string stem = entry.path().stem().string();
    char* end = nullptr;
    const double t_s = std::strtod(stem.c_str(), &end);
    if (stem.empty() || end != stem.c_str() + stem.size() || !std::isfinite(t_s)) {
      throw Error(
          "corrections " + entry.path().string() +
          ": the file's name must be the time the correction became known, in seconds (e.g. 1700000042.500000.tum)");
    }
    CorrectionEvent event;
    event.t_s = t_s;
    event.path = entry.path().string();
    const io::Trajectory poses = io::Trajectory::read(event.path, io::TrajectoryFormat::kTum);
    event.poses = file_describes_body ? poses.transformedBy(T_body_cam) : poses;
    events.push_back(std::move(event));
  }
  if (events.empty()) throw Error("corrections " + dir + ": no correction files (<time in seconds>.tum) in the folder");
  std::sort(events.begin(), events.end(), [](const CorrectionEvent& a, const CorrectionEvent& b) { return a.t_s < b.t_s; });
  for (size_t i = 1; i < events.size(); ++i) {
    if (events[i].t_s == events[i - 1].t_s) {
      throw Error("corrections " + events[i].path + ": the same time as " + events[i - 1].path);
    }
  }
  return events;
}

}  // namespace cenote::pipeline
