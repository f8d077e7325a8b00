// pose_check.h: checks that a camera pose and intrinsic matrix can be used for projection.
// A pose T_world_cam must be finite with an orthonormal, right-handed rotation; K must be a pinhole
// matrix [fx 0 cx; 0 fy cy; 0 0 1] with fx, fy > 0 (skew is rejected: no stage of the pipeline
// models it). Units: metres, pixels.
// Threads: pure functions.
#pragma once

#include <Eigen/Geometry>
#include <string>

namespace cenote {

// Largest allowed |R^T R - I| entry and |det R - 1| (a rotation stored as float and read back
// keeps well below this; an unnormalised quaternion or a scaled matrix does not).
inline constexpr double kRotationTolerance = 1e-5;

// @param what names the pose in the message ("fusion: frame t = 12.300 s").
// @throws cenote::Error "<what>: pose has a non-finite entry" or
//         "<what>: pose rotation is not orthonormal (|R^T R - I| = 0.02, allowed 1e-05)".
void checkPose(const Eigen::Isometry3d& T_world_cam, const std::string& what);

// @throws cenote::Error when K is not a finite pinhole matrix with fx, fy > 0 and zero skew.
void checkIntrinsics(const Eigen::Matrix3d& K, const std::string& what);

}  // namespace cenote
