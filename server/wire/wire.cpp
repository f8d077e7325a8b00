#include "server/wire/wire.h"

#include <cmath>

#include "common/error.h"
#include "common/pose_check.h"

namespace cenote::server {
namespace {

bool isFinite(const v1::Vec3& v) { return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z()); }

}  // namespace

Eigen::Vector3d toEigen(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

void toWire(const Eigen::Vector3d& v, v1::Vec3* out) {
  out->set_x(v.x());
  out->set_y(v.y());
  out->set_z(v.z());
}

void toWire(const mapping::Aabb& box, v1::Box* out) {
  toWire(box.min_m, out->mutable_min());
  toWire(box.max_m, out->mutable_max());
}

void toWire(const mapping::VoxelIndex& ijk, v1::VoxelIndex* out) {
  out->set_x(ijk.x());
  out->set_y(ijk.y());
  out->set_z(ijk.z());
}

v1::VoxelState toWire(mapping::VoxelState state) {
  switch (state) {
    case mapping::VoxelState::kFree: return v1::VOXEL_STATE_FREE;
    case mapping::VoxelState::kOccupied: return v1::VOXEL_STATE_OCCUPIED;
    default: return v1::VOXEL_STATE_UNKNOWN;
  }
}

Eigen::Vector3d finitePoint(const v1::Vec3& v, const std::string& what) {
  if (!isFinite(v)) throw invalidArgument(what + " has a non-finite coordinate");
  return toEigen(v);
}

mapping::Aabb finiteBox(const v1::Box& box, const std::string& what) {
  mapping::Aabb out;
  out.min_m = finitePoint(box.min(), what + ".min");
  out.max_m = finitePoint(box.max(), what + ".max");
  return out;
}

Eigen::Isometry3d finitePose(const v1::Pose& pose, const std::string& what) {
  const Eigen::Vector3d t = finitePoint(pose.position(), what + ".position");
  const v1::Quaternion& q = pose.orientation();
  const Eigen::Quaterniond quat(q.w(), q.x(), q.y(), q.z());
  if (!quat.coeffs().allFinite()) throw invalidArgument(what + ".orientation has a non-finite component");
  if (std::abs(quat.norm() - 1.0) > 1e-3) {
    throw invalidArgument(what + ".orientation is not a unit quaternion (|q| = " + std::to_string(quat.norm()) + ")");
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = quat.normalized().toRotationMatrix();
  T.translation() = t;
  try {
    checkPose(T, what);
  } catch (const Error& e) {
    throw toStatusError(e);
  }
  return T;
}

void checkCount(int64_t count, const std::string& what, int64_t limit, const std::string& limit_name) {
  if (count > limit) {
    throw resourceExhausted(what + ": " + std::to_string(count) + " items, more than the limit " + limit_name + " = " +
                            std::to_string(limit));
  }
}

template <typename Scalar, typename WireScalar>
std::vector<Eigen::Matrix<Scalar, 3, 1>> pointsFromWire(const google::protobuf::RepeatedField<WireScalar>& xyz,
                                                        const std::string& what, int64_t limit,
                                                        const std::string& limit_name) {
  if (xyz.size() % 3 != 0) {
    throw invalidArgument(what + ": " + std::to_string(xyz.size()) + " numbers, not a multiple of 3 (x, y, z per point)");
  }
  const int64_t n = xyz.size() / 3;
  checkCount(n, what, limit, limit_name);
  std::vector<Eigen::Matrix<Scalar, 3, 1>> points(static_cast<size_t>(n));
  const WireScalar* p = xyz.data();
  for (int64_t i = 0; i < n; ++i, p += 3) {
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
      throw invalidArgument(what + ": point " + std::to_string(i) + " has a non-finite coordinate");
    }
    points[i] = Eigen::Matrix<WireScalar, 3, 1>(p[0], p[1], p[2]).template cast<Scalar>();
  }
  return points;
}

template std::vector<Eigen::Vector3d> pointsFromWire<double>(const google::protobuf::RepeatedField<double>&,
                                                             const std::string&, int64_t, const std::string&);
template std::vector<Eigen::Vector3f> pointsFromWire<float>(const google::protobuf::RepeatedField<double>&,
                                                            const std::string&, int64_t, const std::string&);
template std::vector<Eigen::Vector3f> pointsFromWire<float>(const google::protobuf::RepeatedField<float>&,
                                                            const std::string&, int64_t, const std::string&);

}  // namespace cenote::server
