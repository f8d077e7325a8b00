#include "common/pose_check.h"

#include <cmath>
#include <sstream>

#include "common/error.h"

namespace cenote {

void checkPose(const Eigen::Isometry3d& T_world_cam, const std::string& what) {
  const Eigen::Matrix4d& m = T_world_cam.matrix();
  if (!m.allFinite()) throw Error(what + ": pose has a non-finite entry (NaN or inf)");
  if (m(3, 0) != 0.0 || m(3, 1) != 0.0 || m(3, 2) != 0.0 || m(3, 3) != 1.0) {
    throw Error(what + ": pose is not a rigid transform (last row is not 0 0 0 1)");
  }
  const Eigen::Matrix3d R = m.topLeftCorner<3, 3>();
  const double orthogonality = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  const double det = R.determinant();
  if (orthogonality > kRotationTolerance || std::abs(det - 1.0) > kRotationTolerance) {
    std::ostringstream text;
    text << what << ": pose rotation is not orthonormal (|R^T R - I| = " << orthogonality << ", det R = " << det
         << ", allowed deviation " << kRotationTolerance << ")";
    throw Error(text.str());
  }
}

void checkIntrinsics(const Eigen::Matrix3d& K, const std::string& what) {
  const bool ok = K.allFinite() && K(0, 0) > 0.0 && K(1, 1) > 0.0 && K(0, 1) == 0.0 && K(1, 0) == 0.0 && K(2, 0) == 0.0 &&
                  K(2, 1) == 0.0 && K(2, 2) == 1.0;
  if (!ok) {
    std::ostringstream text;
    text << what << ": intrinsic matrix must be [fx 0 cx; 0 fy cy; 0 0 1] with fx, fy > 0, got [" << K.row(0) << "; "
         << K.row(1) << "; " << K.row(2) << "]";
    throw Error(text.str());
  }
}

}  // namespace cenote
