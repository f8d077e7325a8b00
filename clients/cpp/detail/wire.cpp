// wire.cpp: client values <-> protobuf messages.
#include "clients/cpp/detail/wire.h"

#include <algorithm>
#include <cstring>

namespace cenote::client::detail {

void appendFlat(const std::vector<Eigen::Vector3d>& points, size_t begin, size_t end,
                google::protobuf::RepeatedField<double>* out) {
  const size_t old = static_cast<size_t>(out->size());
  out->Resize(static_cast<int>(old + 3 * (end - begin)), 0.0);
  double* dst = out->mutable_data() + old;
  for (size_t i = begin; i < end; ++i, dst += 3) std::memcpy(dst, points[i].data(), 3 * sizeof(double));
}

void toWire(const Segment& segment, v1::Segment* out) {
  toWire(segment.start_m, out->mutable_start());
  toWire(segment.end_m, out->mutable_end());
  out->set_radius_m(segment.radius_m);
}

void toWire(const Ray& ray, v1::Ray* out) {
  toWire(ray.origin_m, out->mutable_origin());
  toWire(ray.direction, out->mutable_direction());
}

void toWire(const PointBatch& batch, v1::PointBatch* out) {
  out->set_timestamp_s(batch.timestamp_s);
  toWire(batch.origin_m, out->mutable_origin());
  // float32: half the bytes of double, and the server's map stores float32 points anyway.
  google::protobuf::RepeatedField<float>* xyz = out->mutable_xyz_f32();
  xyz->Resize(static_cast<int>(3 * batch.points_m.size()), 0.0f);
  float* dst = xyz->mutable_data();
  for (const Eigen::Vector3d& p : batch.points_m) {
    for (int k = 0; k < 3; ++k) *dst++ = static_cast<float>(p[k]);
  }
  out->clear_xyz();
  std::string* rgb = out->mutable_rgb();
  rgb->resize(3 * batch.rgb.size());
  if (!batch.rgb.empty()) std::memcpy(rgb->data(), batch.rgb.data(), rgb->size());
}

void toWire(const Pose& pose, v1::Pose* out) {
  toWire(pose.position_m, out->mutable_position());
  v1::Quaternion* q = out->mutable_orientation();
  q->set_x(pose.orientation.x());
  q->set_y(pose.orientation.y());
  q->set_z(pose.orientation.z());
  q->set_w(pose.orientation.w());
}

// ImageEncoding's values are the wire's (toWire() casts one into the other).
static_assert(static_cast<int>(ImageEncoding::kRgb8) == v1::IMAGE_ENCODING_RGB8 &&
              static_cast<int>(ImageEncoding::kBayerGrbg8) == v1::IMAGE_ENCODING_BAYER_GRBG8);

void toWire(const Image& image, v1::Image* out) {
  if (!image.encoded.empty()) {
    out->set_encoded(image.encoded);
    return;
  }
  v1::RawImage* raw = out->mutable_raw();
  raw->set_width(image.width);
  raw->set_height(image.height);
  raw->set_encoding(static_cast<v1::ImageEncoding>(image.encoding));
  raw->set_data(image.raw);
}

void toWire(const StereoFrame& frame, v1::StereoFrame* out) {
  out->set_timestamp_s(frame.timestamp_s);
  toWire(frame.left, out->mutable_left());
  toWire(frame.right, out->mutable_right());
  if (frame.has_pose) toWire(frame.T_world_cam, out->mutable_pose());
}

void toWire(const PoseStamped& pose, v1::PoseStamped* out) {
  out->set_timestamp_s(pose.timestamp_s);
  toWire(pose.T_world_cam, out->mutable_pose());
}

BoxCounts fromWire(const v1::BoxCounts& counts) {
  return {counts.unknown(), counts.free(), counts.occupied(), counts.any_occupied()};
}

Collision fromWire(const v1::Collision& c) {
  Collision out;
  out.hit = c.hit();
  out.hit_distance_m = c.hit_distance_m();
  out.hit_voxel = fromWire(c.hit_voxel());
  out.hit_point_m = fromWire(c.hit_point());
  out.crossed_unknown = c.crossed_unknown();
  out.unknown_distance_m = c.unknown_distance_m();
  out.stopped_at_unknown = c.stopped_at_unknown();
  out.clear = c.clear();
  return out;
}

Frontier fromWire(const v1::Frontier& f) {
  Frontier out;
  out.id = f.id();
  out.num_voxels = f.num_voxels();
  out.centroid_m = fromWire(f.centroid());
  out.bounds = fromWire(f.bounds());
  out.direction = fromWire(f.direction());
  out.distance_m = f.distance_m();
  return out;
}

MapInfo fromWire(const v1::MapInfo& info) {
  MapInfo out;
  out.voxel_size_m = info.voxel_size_m();
  out.frame_id = info.frame_id();
  out.bounds = fromWire(info.bounds());
  out.occupied = info.occupied();
  out.free = info.free();
  out.prob_hit = info.prob_hit();
  out.prob_miss = info.prob_miss();
  out.clamp_min = info.clamp_min();
  out.clamp_max = info.clamp_max();
  out.occupied_threshold = info.occupied_threshold();
  out.max_range_m = info.max_range_m();
  out.max_distance_m = info.max_distance_m();
  out.map_version = info.map_version();
  return out;
}

ServerStats fromWire(const v1::Stats& s) {
  ServerStats out;
  out.uptime_s = s.uptime_s();
  out.frames_received = s.frames_received();
  out.frames_processed = s.frames_processed();
  out.frames_skipped = s.frames_skipped();
  out.frames_rejected = s.frames_rejected();
  out.batches_integrated = s.batches_integrated();
  out.poses_received = s.poses_received();
  out.occupied = s.occupied();
  out.free = s.free();
  out.map_memory_bytes = s.map_memory_bytes();
  out.process_memory_bytes = s.process_memory_bytes();
  out.map_version = s.map_version();
  for (const auto& stage : s.stages())
    out.stages.push_back({stage.name(), stage.median_ms(), stage.p95_ms(), stage.count()});
  for (const auto& m : s.methods()) out.methods.push_back({m.method(), m.calls(), m.errors(), m.p50_ms(), m.p99_ms()});
  out.subscribers = s.subscribers();
  out.last_snapshot_age_s = s.last_snapshot_age_s();
  return out;
}

ChangeResult fromWire(const v1::ChangeReply& reply) {
  return {reply.changed_blocks(), fromWire(reply.changed_bounds()), reply.map_version()};
}

BatchAck fromWire(const v1::BatchAck& ack) {
  BatchAck out;
  out.sequence = ack.sequence();
  out.timestamp_s = ack.timestamp_s();
  out.status_code = ack.status_code();
  out.message = ack.message();
  out.voxels_updated = ack.voxels_updated();
  out.changed_blocks = ack.changed_blocks();
  out.map_version = ack.map_version();
  return out;
}

FrameAck fromWire(const v1::FrameAck& ack) {
  FrameAck out;
  out.sequence = ack.sequence();
  out.timestamp_s = ack.timestamp_s();
  out.outcome = static_cast<FrameOutcome>(ack.outcome());
  out.status_code = ack.status_code();
  out.message = ack.message();
  out.map_version = ack.map_version();
  return out;
}

PoseAck fromWire(const v1::PoseAck& ack) { return {ack.sequence(), ack.timestamp_s(), ack.status_code(), ack.message()}; }

void fromWire(const v1::MapUpdate& update, MapUpdate& out) {
  out.sequence = update.sequence();
  out.snapshot = update.snapshot();
  out.snapshot_complete = update.snapshot_complete();
  out.resync = update.resync();
  out.changed_bounds = fromWire(update.changed_bounds());
  out.voxel_size_m = update.voxel_size_m();
  out.blocks.resize(static_cast<size_t>(update.blocks_size()));
  for (int b = 0; b < update.blocks_size(); ++b) {
    const v1::Block& in = update.blocks(b);
    UpdateBlock& block = out.blocks[static_cast<size_t>(b)];
    block.index = fromWire(in.index());
    // A malformed block (not 512 states) reads as unknown beyond what was sent.
    block.states.fill(VoxelState::kUnknown);
    const std::string& states = in.states();
    const size_t n = std::min<size_t>(states.size(), 512);
    for (size_t i = 0; i < n; ++i) {
      const auto v = static_cast<uint8_t>(states[i]);
      block.states[i] = v <= 2 ? static_cast<VoxelState>(v) : VoxelState::kUnknown;
    }
    block.probabilities.assign(in.probabilities().begin(), in.probabilities().end());
  }
}

}  // namespace cenote::client::detail
