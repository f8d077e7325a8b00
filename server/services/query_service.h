// query_service.h: Query (proto/cenote/v1/query.proto): voxel states, boxes, segments and capsules,
// raycasts, distances, frontiers, voxel extracts and the map's metadata, all batched, served
// concurrently with ingest. Work is bounded per request: boxes, segments, rays and extracts count
// the voxels they may visit before visiting any (server.limits.max_query_voxels), and run in slices
// (mapping/query/map_query.h) that each hold the map's shared lock, so integration and other
// readers get in between; between two slices the call's deadline (DEADLINE_EXCEEDED) and
// cancellation (CANCELLED) are checked.
// Threads: any number of calls at once.
#pragma once

#include <algorithm>

#include "cenote/v1/query.grpc.pb.h"
#include "mapping/query/map_query.h"
#include "server/access/call_guard.h"
#include "server/host/map_host.h"
#include "server/server_config.h"

namespace cenote::server {

// Worst-case size of an ExtractReply (proto/cenote/v1/query.proto) per listed voxel: ijk, three
// packed sint32 varints of at most 3 bytes each (zigzag of |i| <= kMaxVoxelIndex + 1 < 2^20 fits in
// 21 bits); its state, a 1-byte packed enum; its probability, a 4-byte packed float; its colour,
// 3 bytes of rgb.
inline constexpr int64_t kExtractBytesPerVoxel = 3 * 3 + 1 + 4 + 3;
// And once per reply: voxel_size_m (tag + 8), map_version (tag + at most 10), the tags and length
// varints (at most 1 + 5 each) of the four per-voxel fields: 44 bytes, rounded up.
inline constexpr int64_t kExtractReplyBytes = 64;
// Voxels an ExtractVoxels box may hold: max_box_voxels, and fewer when its reply at the worst
// would exceed max_message_bytes.
inline int64_t maxExtractVoxels(const RequestLimits& limits) {
  return std::min(limits.max_box_voxels, (limits.max_message_bytes - kExtractReplyBytes) / kExtractBytesPerVoxel);
}

class QueryService final : public v1::Query::Service {
 public:
  QueryService(MapHost& host, CallGuard& guard, const ServerConfig& config, std::string frame_id)
      : host_(host), guard_(guard), limits_(config.limits), frame_id_(std::move(frame_id)) {}

  grpc::Status GetVoxels(grpc::ServerContext* context, const v1::VoxelsRequest* request, v1::VoxelsReply* reply) override;
  grpc::Status GetBoxes(grpc::ServerContext* context, const v1::BoxesRequest* request, v1::BoxesReply* reply) override;
  grpc::Status CheckSegments(grpc::ServerContext* context, const v1::SegmentsRequest* request,
                             v1::CollisionsReply* reply) override;
  grpc::Status Raycast(grpc::ServerContext* context, const v1::RaycastRequest* request,
                       v1::CollisionsReply* reply) override;
  grpc::Status GetDistances(grpc::ServerContext* context, const v1::DistancesRequest* request,
                            v1::DistancesReply* reply) override;
  grpc::Status GetFrontiers(grpc::ServerContext* context, const v1::FrontiersRequest* request,
                            v1::FrontiersReply* reply) override;
  grpc::Status ExtractVoxels(grpc::ServerContext* context, const v1::ExtractRequest* request,
                             v1::ExtractReply* reply) override;
  grpc::Status GetMapInfo(grpc::ServerContext* context, const v1::MapInfoRequest* request, v1::MapInfo* reply) override;

 private:
  // Voxels whose centre lies in `box`: RESOURCE_EXHAUSTED beyond limits.max_box_voxels.
  void checkBoxVolume(const mapping::Aabb& box, const std::string& what) const;
  void waitForDerived(grpc::ServerContext* context) const;
  // The budget and slices of one batch; between slices, the deadline and cancellation of `context`
  // (the error names `method` and how many of `items` were answered).
  mapping::BatchControl batchControl(grpc::ServerContext* context, const char* method, size_t items) const;

  MapHost& host_;
  CallGuard& guard_;
  const RequestLimits limits_;
  const std::string frame_id_;
};

}  // namespace cenote::server
