#include "pipeline/frame/frame_admission.h"

#include <cmath>
#include <limits>

namespace cenote::pipeline {

const char* toString(Admission admission) {
  switch (admission) {
    case Admission::kAdmitted: return "admitted";
    case Admission::kOutOfOrder: return "out of time order";
    case Admission::kNoPose: return "no pose";
    case Admission::kNotKeyframe: return "not a keyframe";
  }
  return "?";
}

Eigen::Isometry3d rectifiedFromRaw(const Rectifier& rectifier) {
  Eigen::Isometry3d T_raw_rect = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) T_raw_rect.linear()(r, c) = rectifier.R_rect_left()(c, r);
  }
  return T_raw_rect;
}

FrameAdmission::FrameAdmission(const Rectifier& rectifier, const RunConfig& run)
    : rectifier_(rectifier),
      T_raw_rect_(rectifiedFromRaw(rectifier)),
      keyframes_(run),
      last_t_s_(-std::numeric_limits<double>::infinity()) {}

FrameDecision FrameAdmission::decide(double t_s, const PoseLookup& pose_at) {
  FrameDecision decision;
  if (!std::isfinite(t_s) || !(t_s > last_t_s_)) return decision;  // kOutOfOrder
  last_t_s_ = t_s;
  const std::optional<Eigen::Isometry3d> T_world_raw = pose_at(t_s);
  if (!T_world_raw) {
    decision.admission = Admission::kNoPose;
    return decision;
  }
  decision.T_world_raw = *T_world_raw;
  decision.admission = keyframes_.wouldAccept(*T_world_raw) ? Admission::kAdmitted : Admission::kNotKeyframe;
  return decision;
}

PosedPair FrameAdmission::admit(const StereoFrame& raw, const Eigen::Isometry3d& T_world_raw) {
  PosedPair posed;
  posed.pair = rectifier_.rectify(raw);
  posed.T_world_cam = T_world_raw * T_raw_rect_;
  keyframes_.keep(T_world_raw);
  return posed;
}

}  // namespace cenote::pipeline
