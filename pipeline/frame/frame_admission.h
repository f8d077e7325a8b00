// frame_admission.h: the one step every stereo frame takes from its source into the pipeline,
// whoever feeds it (`cenote run` reading a dataset, the server's frame stream, a recording):
//
//   timestamp ─► time order ─► pose? ─► keyframe? ─► (source reads or decodes the images)
//             ─► rectification ─► T_world_cam = T_world_raw * T_raw_rect ─► PosedPair
//
// Sources differ only in where a frame's images and pose come from (a file, the wire, a buffer of
// streamed poses); what is decided with them is written here once, so the same frames with the
// same poses give the same points bit for bit whichever way they came in.
// decide() runs before the images are read, so frames that go no further cost no decoding.
// Units: seconds, metres, degrees. Poses: T_world_raw of the raw left camera; the PosedPair's
// T_world_cam is that of the rectified left camera.
// Threads: one user at a time (it remembers the last timestamp and the last keyframe).
#pragma once

#include <Eigen/Geometry>
#include <functional>
#include <optional>

#include "pipeline/calibration/rectifier.h"
#include "pipeline/frame/frames.h"
#include "pipeline/frame/keyframe_selector.h"
#include "pipeline/runner/run_config.h"

namespace cenote::pipeline {

// What decide() made of a frame.
enum class Admission {
  kAdmitted,     // goes on: read its images and call admit()
  kOutOfOrder,   // its timestamp is not finite or not after the previous frame's
  kNoPose,       // no pose of its own and none could be interpolated at its time
  kNotKeyframe,  // moved less than the keyframe thresholds since the last admitted frame
};

const char* toString(Admission admission);

struct FrameDecision {
  Admission admission = Admission::kOutOfOrder;
  Eigen::Isometry3d T_world_raw = Eigen::Isometry3d::Identity();  // the pose found (kAdmitted, kNotKeyframe)
};

// Where a source finds the raw left camera's pose at a time: a trajectory's interpolation, a
// frame's own pose, a buffer of streamed poses. nullopt: none. May throw; the error reaches the
// caller of decide().
using PoseLookup = std::function<std::optional<Eigen::Isometry3d>(double t_s)>;

// The rectified left camera in the raw left camera's frame: p_rect = R1 p_raw, so the rectified
// camera is the raw one rotated by R1^T. T_world_rect = T_world_raw * rectifiedFromRaw(r).
Eigen::Isometry3d rectifiedFromRaw(const Rectifier& rectifier);

class FrameAdmission {
 public:
  // @param rectifier must outlive this object.
  FrameAdmission(const Rectifier& rectifier, const RunConfig& run);

  // Time order first, then the pose (pose_at is asked only for a frame in time order), then the
  // keyframe choice. Every frame in time order, refused later or not, sets the time the next one
  // must come after.
  FrameDecision decide(double t_s, const PoseLookup& pose_at);

  // Rectifies a frame that decide() admitted and poses its rectified left camera; the frame then
  // becomes the keyframe the next ones are measured from (a frame whose images could not be read
  // or rectified does not).
  // @throws cenote::Error when the images are empty or not of the calibrated size.
  PosedPair admit(const StereoFrame& raw, const Eigen::Isometry3d& T_world_raw);

  // Timestamp of the last frame decide() saw; -inf before the first.
  double lastTimestamp() const { return last_t_s_; }

 private:
  const Rectifier& rectifier_;
  const Eigen::Isometry3d T_raw_rect_;
  KeyframeSelector keyframes_;
  double last_t_s_;
};

}  // namespace cenote::pipeline
