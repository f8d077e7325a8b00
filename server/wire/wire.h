// wire.h: conversions between the wire types (proto/cenote/v1) and the map's types, with the checks
// every request gets: finite coordinates, batch sizes within the limits. A failed check throws a
// StatusError whose message names the field and the item (e.g. "xyz: point 3 has a non-finite
// coordinate", "xyz: 200000 points, more than the limit server.limits.max_batch = 100000").
// Units: metres, world frame. Threads: pure functions.
#pragma once

#include <google/protobuf/repeated_field.h>

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "cenote/v1/types.pb.h"
#include "mapping/voxel_types.h"
#include "server/wire/status_error.h"

namespace cenote::server {

Eigen::Vector3d toEigen(const v1::Vec3& v);
void toWire(const Eigen::Vector3d& v, v1::Vec3* out);
void toWire(const mapping::Aabb& box, v1::Box* out);
void toWire(const mapping::VoxelIndex& ijk, v1::VoxelIndex* out);
v1::VoxelState toWire(mapping::VoxelState state);

// @throws StatusError INVALID_ARGUMENT naming `what` when a coordinate is not finite.
Eigen::Vector3d finitePoint(const v1::Vec3& v, const std::string& what);
// A box with finite corners; min > max on an axis is an empty box (allowed).
mapping::Aabb finiteBox(const v1::Box& box, const std::string& what);
// Pose T_world_cam from position + unit quaternion (|q| within 1e-3 of 1, then normalised).
Eigen::Isometry3d finitePose(const v1::Pose& pose, const std::string& what);

// Flat x, y, z triples (double, or a PointBatch's xyz_f32) into points (double for queries, float
// for a PointBatch: converted in the same pass). @throws StatusError: INVALID_ARGUMENT when the
// length is not a multiple of 3 or a coordinate is not finite; RESOURCE_EXHAUSTED when there are
// more than `limit` points (the message names `limit_name`). Instantiated for double -> double,
// double -> float and float -> float.
template <typename Scalar = double, typename WireScalar = double>
std::vector<Eigen::Matrix<Scalar, 3, 1>> pointsFromWire(const google::protobuf::RepeatedField<WireScalar>& xyz,
                                                        const std::string& what, int64_t limit,
                                                        const std::string& limit_name);

// @throws StatusError RESOURCE_EXHAUSTED when count > limit.
void checkCount(int64_t count, const std::string& what, int64_t limit, const std::string& limit_name);

}  // namespace cenote::server
