// wire.h: conversions between the client's plain values (client_types.h) and the generated
// protobuf messages. Private to the client library: only its .cpp files include it.
// Threads: pure functions.
#pragma once

#include "cenote/v1/admin.pb.h"
#include "cenote/v1/ingest.pb.h"
#include "cenote/v1/query.pb.h"
#include "cenote/v1/types.pb.h"
#include "cenote/v1/updates.pb.h"
#include "clients/cpp/client_types.h"

namespace cenote::client::detail {

inline void toWire(const Eigen::Vector3d& v, v1::Vec3* out) {
  out->set_x(v.x());
  out->set_y(v.y());
  out->set_z(v.z());
}
inline Eigen::Vector3d fromWire(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }
inline Eigen::Vector3i fromWire(const v1::VoxelIndex& v) { return {v.x(), v.y(), v.z()}; }
inline void toWire(const Box& box, v1::Box* out) {
  toWire(box.min_m, out->mutable_min());
  toWire(box.max_m, out->mutable_max());
}
inline Box fromWire(const v1::Box& box) { return {fromWire(box.min()), fromWire(box.max())}; }

// Appends points [begin, end) as flat x, y, z.
void appendFlat(const std::vector<Eigen::Vector3d>& points, size_t begin, size_t end,
                google::protobuf::RepeatedField<double>* out);
void toWire(const Segment& segment, v1::Segment* out);
void toWire(const Ray& ray, v1::Ray* out);
void toWire(const PointBatch& batch, v1::PointBatch* out);
void toWire(const Pose& pose, v1::Pose* out);
void toWire(const Image& image, v1::Image* out);
void toWire(const StereoFrame& frame, v1::StereoFrame* out);
void toWire(const PoseStamped& pose, v1::PoseStamped* out);

BoxCounts fromWire(const v1::BoxCounts& counts);
Collision fromWire(const v1::Collision& collision);
Frontier fromWire(const v1::Frontier& frontier);
MapInfo fromWire(const v1::MapInfo& info);
ServerStats fromWire(const v1::Stats& stats);
ChangeResult fromWire(const v1::ChangeReply& reply);
BatchAck fromWire(const v1::BatchAck& ack);
FrameAck fromWire(const v1::FrameAck& ack);
PoseAck fromWire(const v1::PoseAck& ack);
// Fills `out` (reusing its blocks' storage).
void fromWire(const v1::MapUpdate& update, MapUpdate& out);

}  // namespace cenote::client::detail
