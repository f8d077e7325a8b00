#include "server/services/query_service.h"

#include <chrono>
#include <cmath>

#include "server/wire/wire.h"

namespace cenote::server {
namespace {

void toWire(const mapping::CollisionResult& r, const mapping::OccupancyMap& map, v1::Collision* out) {
  out->set_hit(r.hit);
  out->set_hit_distance_m(r.hit_distance_m);
  if (r.hit) {
    server::toWire(r.hit_voxel, out->mutable_hit_voxel());
    server::toWire(map.toPoint(r.hit_voxel), out->mutable_hit_point());
  }
  out->set_crossed_unknown(r.crossed_unknown);
  out->set_unknown_distance_m(r.unknown_distance_m);
  out->set_stopped_at_unknown(r.stopped_at_unknown);
  out->set_clear(r.isClear());
}

// Between two slices of a batch: DEADLINE_EXCEEDED once the call's deadline passed, CANCELLED once
// the client cancelled (or went away).
void checkInterrupted(grpc::ServerContext* context, const char* method, size_t done, size_t items,
                      const char* unit = "items") {
  const std::string progress = " after " + std::to_string(done) + " of " + std::to_string(items) + " " + unit;
  if (std::chrono::system_clock::now() > context->deadline()) {
    throw StatusError(grpc::StatusCode::DEADLINE_EXCEEDED, std::string(method) + ": the deadline passed" + progress);
  }
  if (context->IsCancelled()) {
    throw StatusError(grpc::StatusCode::CANCELLED, std::string(method) + ": cancelled by the client" + progress);
  }
}

}  // namespace

void QueryService::checkBoxVolume(const mapping::Aabb& box, const std::string& what) const {
  if (box.isEmpty()) return;
  const double s = host_.map().voxelSize();
  double voxels = 1.0;
  for (int a = 0; a < 3; ++a) voxels *= std::floor((box.max_m[a] - box.min_m[a]) / s) + 1.0;
  if (voxels > static_cast<double>(limits_.max_box_voxels)) {
    throw resourceExhausted(
        what + ": about " + std::to_string(static_cast<int64_t>(voxels)) +
        " voxels, more than the limit server.limits.max_box_voxels = " + std::to_string(limits_.max_box_voxels));
  }
}

mapping::BatchControl QueryService::batchControl(grpc::ServerContext* context, const char* method, size_t items) const {
  mapping::BatchControl control;
  control.max_voxels = static_cast<uint64_t>(limits_.max_query_voxels);
  control.budget_name = "server.limits.max_query_voxels";
  control.between_slices = [context, method, items](size_t done) { checkInterrupted(context, method, done, items); };
  return control;
}

void QueryService::waitForDerived(grpc::ServerContext* context) const {
  if (!host_.waitForDerived(context->deadline())) {
    throw StatusError(grpc::StatusCode::DEADLINE_EXCEEDED,
                      "the distance field and frontiers did not catch up with the map before the deadline");
  }
}

grpc::Status QueryService::GetVoxels(grpc::ServerContext* context, const v1::VoxelsRequest* request,
                                     v1::VoxelsReply* reply) {
  return guard_.run(context, "Query/GetVoxels", [&] {
    const auto points = pointsFromWire(request->xyz(), "xyz", limits_.max_batch, "server.limits.max_batch");
    reply->set_map_version(host_.map().version());
    const std::vector<mapping::VoxelQuery> results = mapping::queryVoxels(host_.map(), points);
    reply->mutable_states()->Reserve(static_cast<int>(results.size()));
    reply->mutable_probabilities()->Reserve(static_cast<int>(results.size()));
    for (const mapping::VoxelQuery& r : results) {
      reply->add_states(server::toWire(r.state));
      reply->add_probabilities(static_cast<float>(r.probability));
    }
    return grpc::Status::OK;
  });
}

grpc::Status QueryService::GetBoxes(grpc::ServerContext* context, const v1::BoxesRequest* request, v1::BoxesReply* reply) {
  return guard_.run(context, "Query/GetBoxes", [&] {
    checkCount(request->boxes_size(), "boxes", limits_.max_batch, "server.limits.max_batch");
    std::vector<mapping::Aabb> boxes;
    for (int i = 0; i < request->boxes_size(); ++i) {
      const std::string what = "boxes[" + std::to_string(i) + "]";
      boxes.push_back(finiteBox(request->boxes(i), what));
      checkBoxVolume(boxes.back(), what);
    }
    reply->set_map_version(host_.map().version());
    const auto control = batchControl(context, "Query/GetBoxes", boxes.size());
    for (const mapping::BoxCounts& c : mapping::queryBoxes(host_.map(), boxes, control)) {
      v1::BoxCounts* out = reply->add_counts();
      out->set_unknown(c.unknown);
      out->set_free(c.free);
      out->set_occupied(c.occupied);
      out->set_any_occupied(c.anyOccupied());
    }
    return grpc::Status::OK;
  });
}

grpc::Status QueryService::CheckSegments(grpc::ServerContext* context, const v1::SegmentsRequest* request,
                                         v1::CollisionsReply* reply) {
  return guard_.run(context, "Query/CheckSegments", [&] {
    checkCount(request->segments_size(), "segments", limits_.max_batch, "server.limits.max_batch");
    std::vector<mapping::SegmentQuery> segments(request->segments_size());
    for (int i = 0; i < request->segments_size(); ++i) {
      const v1::Segment& s = request->segments(i);
      const std::string what = "segments[" + std::to_string(i) + "]";
      segments[i].start_m = finitePoint(s.start(), what + ".start");
      segments[i].end_m = finitePoint(s.end(), what + ".end");
      if (!(s.radius_m() >= 0.0) || !std::isfinite(s.radius_m())) {
        throw invalidArgument(what + ".radius_m = " + std::to_string(s.radius_m()) + ": must be finite and >= 0");
      }
      segments[i].radius_m = s.radius_m();
      // A capsule visits every voxel of its bounding box's slabs.
      if (s.radius_m() > 0.0) checkBoxVolume(mapping::boundsOf(segments[i]), what);
    }
    reply->set_map_version(host_.map().version());
    const auto control = batchControl(context, "Query/CheckSegments", segments.size());
    for (const auto& r : mapping::checkSegments(host_.map(), segments, request->stop_at_unknown(), control)) {
      toWire(r, host_.map(), reply->add_results());
    }
    return grpc::Status::OK;
  });
}

grpc::Status QueryService::Raycast(grpc::ServerContext* context, const v1::RaycastRequest* request,
                                   v1::CollisionsReply* reply) {
  return guard_.run(context, "Query/Raycast", [&] {
    checkCount(request->rays_size(), "rays", limits_.max_batch, "server.limits.max_batch");
    if (!(request->max_range_m() > 0.0) || !std::isfinite(request->max_range_m())) {
      throw invalidArgument("max_range_m = " + std::to_string(request->max_range_m()) + ": must be finite and > 0");
    }
    std::vector<mapping::Ray> rays(request->rays_size());
    for (int i = 0; i < request->rays_size(); ++i) {
      const std::string what = "rays[" + std::to_string(i) + "]";
      rays[i].origin_m = finitePoint(request->rays(i).origin(), what + ".origin");
      rays[i].direction = finitePoint(request->rays(i).direction(), what + ".direction");
      if (rays[i].direction.norm() == 0.0) throw invalidArgument(what + ".direction is zero");
    }
    reply->set_map_version(host_.map().version());
    const auto control = batchControl(context, "Query/Raycast", rays.size());
    for (const auto& r : mapping::raycast(host_.map(), rays, request->max_range_m(), request->stop_at_unknown(), control)) {
      toWire(r, host_.map(), reply->add_results());
    }
    return grpc::Status::OK;
  });
}

grpc::Status QueryService::GetDistances(grpc::ServerContext* context, const v1::DistancesRequest* request,
                                        v1::DistancesReply* reply) {
  return guard_.run(context, "Query/GetDistances", [&] {
    const auto points = pointsFromWire(request->xyz(), "xyz", limits_.max_batch, "server.limits.max_batch");
    waitForDerived(context);
    reply->set_map_version(host_.map().version());
    reply->set_max_distance_m(host_.distanceField().maxDistance());
    for (const mapping::DistanceQuery& d : host_.distanceField().query(points)) {
      reply->add_distances_m(static_cast<float>(d.distance_m));
      for (int a = 0; a < 3; ++a) reply->add_gradients(static_cast<float>(d.gradient[a]));
      reply->add_within_max(d.within_max);
    }
    return grpc::Status::OK;
  });
}

grpc::Status QueryService::GetFrontiers(grpc::ServerContext* context, const v1::FrontiersRequest* request,
                                        v1::FrontiersReply* reply) {
  return guard_.run(context, "Query/GetFrontiers", [&] {
    const Eigen::Vector3d position = finitePoint(request->position(), "position");
    std::optional<mapping::Aabb> region;
    if (request->has_region()) region = finiteBox(request->region(), "region");
    waitForDerived(context);
    reply->set_map_version(host_.map().version());
    for (const mapping::FrontierCluster& c : host_.frontiers().clusters(position)) {
      if (region && !region->contains(c.centroid_m)) continue;
      if (request->max_clusters() > 0 && reply->frontiers_size() >= static_cast<int>(request->max_clusters())) break;
      v1::Frontier* f = reply->add_frontiers();
      f->set_id(c.id);
      f->set_num_voxels(c.num_voxels);
      server::toWire(c.centroid_m, f->mutable_centroid());
      server::toWire(c.bounds_m, f->mutable_bounds());
      server::toWire(c.direction, f->mutable_direction());
      f->set_distance_m(c.distance_m);
    }
    return grpc::Status::OK;
  });
}

grpc::Status QueryService::ExtractVoxels(grpc::ServerContext* context, const v1::ExtractRequest* request,
                                         v1::ExtractReply* reply) {
  return guard_.run(context, "Query/ExtractVoxels", [&] {
    const mapping::OccupancyMap& map = host_.map();
    const mapping::BoxVoxels voxels = mapping::voxelsOfBox(finiteBox(request->box(), "box"), map.voxelSize(), "box");
    if (!voxels.within_range) throw invalidArgument("box reaches beyond " + mapping::mapRangeText(map));
    // One item: its reply must fit one message at the worst (every voxel listed).
    const int64_t limit = maxExtractVoxels(limits_);
    if (voxels.count() > static_cast<uint64_t>(limit)) {
      throw resourceExhausted("box: " + std::to_string(voxels.count()) +
                              " voxels, more than an extract may hold: " + std::to_string(limit) +
                              " (server.limits.max_box_voxels = " + std::to_string(limits_.max_box_voxels) +
                              ", and (server.limits.max_message_bytes = " + std::to_string(limits_.max_message_bytes) +
                              " - " + std::to_string(kExtractReplyBytes) + ") / " + std::to_string(kExtractBytesPerVoxel) +
                              " bytes per voxel at the worst)");
    }
    checkCount(static_cast<int64_t>(voxels.count()), "box voxels", limits_.max_query_voxels,
               "server.limits.max_query_voxels");
    reply->set_voxel_size_m(map.voxelSize());
    if (voxels.voxels.isEmpty()) return grpc::Status::OK;
    const mapping::VoxelIndex lo = voxels.voxels.min, hi = voxels.voxels.max;
    const mapping::OccupancyMap::ConstAccessor access = map.constAccessor();
    reply->set_map_version(map.version());
    std::string rgb;
    for (int x = lo.x(); x <= hi.x(); ++x) {
      checkInterrupted(context, "Query/ExtractVoxels", x - lo.x(), hi.x() - lo.x() + 1, "x planes");
      for (int y = lo.y(); y <= hi.y(); ++y) {
        for (int z = lo.z(); z <= hi.z(); ++z) {
          const mapping::VoxelIndex ijk(x, y, z);
          const mapping::VoxelState state = access.state(ijk);
          if (state == mapping::VoxelState::kUnknown && !request->include_unknown()) continue;
          reply->add_ijk(x);
          reply->add_ijk(y);
          reply->add_ijk(z);
          reply->add_states(server::toWire(state));
          reply->add_probabilities(static_cast<float>(access.probability(ijk)));
          std::array<uint8_t, 3> color{0, 0, 0};
          access.color(ijk, color);
          rgb.append(reinterpret_cast<const char*>(color.data()), 3);
        }
      }
    }
    reply->set_rgb(std::move(rgb));
    return grpc::Status::OK;
  });
}

grpc::Status QueryService::GetMapInfo(grpc::ServerContext* context, const v1::MapInfoRequest*, v1::MapInfo* reply) {
  return guard_.run(context, "Query/GetMapInfo", [&] {
    const mapping::OccupancyMap& map = host_.map();
    const mapping::MapConfig& c = map.config();
    const mapping::MapStats stats = map.stats();
    reply->set_voxel_size_m(c.voxel_size_m);
    reply->set_frame_id(frame_id_);
    server::toWire(stats.bounds_m, reply->mutable_bounds());
    reply->set_occupied(stats.occupied);
    reply->set_free(stats.free);
    reply->set_prob_hit(c.prob_hit);
    reply->set_prob_miss(c.prob_miss);
    reply->set_clamp_min(c.clamp_min);
    reply->set_clamp_max(c.clamp_max);
    reply->set_occupied_threshold(c.occupied_threshold);
    reply->set_max_range_m(c.max_range_m);
    reply->set_max_distance_m(c.max_distance_m);
    reply->set_map_version(map.version());
    return grpc::Status::OK;
  });
}

}  // namespace cenote::server
