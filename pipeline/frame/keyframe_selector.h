// keyframe_selector.h: keeps a frame when the camera moved at least a translation or a rotation
// threshold since the last kept frame (the paper used SVIn2's keyframes this way); with no
// threshold set, every frame is kept. Units: metres, degrees.
// Threads: one user at a time.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <optional>

#include "pipeline/runner/run_config.h"

namespace cenote::pipeline {

inline double rotationDeg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() * 180.0 / M_PI;
}

// Skips frames that moved less than both thresholds since the last keyframe (none set: none skipped).
class KeyframeSelector {
 public:
  explicit KeyframeSelector(const RunConfig& c)
      : translation_m_(c.keyframe_translation_m), rotation_deg_(c.keyframe_rotation_deg) {}

  // Whether a frame at `pose` would be a keyframe (the first frame always is).
  bool wouldAccept(const Eigen::Isometry3d& pose) const {
    if ((translation_m_ <= 0.0 && rotation_deg_ <= 0.0) || !last_) return true;
    return (translation_m_ > 0.0 && (pose.translation() - last_->translation()).norm() >= translation_m_) ||
           (rotation_deg_ > 0.0 && rotationDeg(*last_, pose) >= rotation_deg_);
  }
  // Makes `pose` the keyframe the next frames are measured from.
  void keep(const Eigen::Isometry3d& pose) { last_ = pose; }

 private:
  double translation_m_, rotation_deg_;
  std::optional<Eigen::Isometry3d> last_;
};

}  // namespace cenote::pipeline
