// admin_service.h: Admin (proto/cenote/v1/admin.proto): snapshots written on the server or streamed
// to the client, clearing, cropping, reset, and statistics of the running server.
// Threads: any number of calls at once; snapshot writes serialise (snapshotter.h); at most
// max_downloads DownloadSnapshot calls at once (more: RESOURCE_EXHAUSTED).
#pragma once

#include <atomic>
#include <chrono>

#include "cenote/v1/admin.grpc.pb.h"
#include "server/access/call_guard.h"
#include "server/services/ingest_service.h"
#include "server/host/map_host.h"
#include "server/host/snapshotter.h"

namespace cenote::server {

class AdminService final : public v1::Admin::Service {
 public:
  // max_downloads: concurrent DownloadSnapshot calls (server.limits.max_snapshot_downloads).
  AdminService(MapHost& host, CallGuard& guard, Snapshotter& snapshots, const IngestService& ingest, int max_downloads)
      : host_(host),
        guard_(guard),
        snapshots_(snapshots),
        ingest_(ingest),
        max_downloads_(max_downloads),
        started_(std::chrono::steady_clock::now()) {}

  grpc::Status Snapshot(grpc::ServerContext* context, const v1::SnapshotRequest* request,
                        v1::SnapshotReply* reply) override;
  grpc::Status DownloadSnapshot(grpc::ServerContext* context, const v1::SnapshotRequest* request,
                                grpc::ServerWriter<v1::FileChunk>* writer) override;
  grpc::Status ClearBox(grpc::ServerContext* context, const v1::ClearBoxRequest* request, v1::ChangeReply* reply) override;
  grpc::Status ClearSphere(grpc::ServerContext* context, const v1::ClearSphereRequest* request,
                           v1::ChangeReply* reply) override;
  grpc::Status Crop(grpc::ServerContext* context, const v1::CropRequest* request, v1::ChangeReply* reply) override;
  grpc::Status Reset(grpc::ServerContext* context, const v1::ResetRequest* request, v1::ChangeReply* reply) override;
  grpc::Status GetStats(grpc::ServerContext* context, const v1::StatsRequest* request, v1::Stats* reply) override;

 private:
  void fillChange(const mapping::MapDelta& delta, v1::ChangeReply* reply) const;

  MapHost& host_;
  CallGuard& guard_;
  Snapshotter& snapshots_;
  const IngestService& ingest_;
  const int max_downloads_;
  std::atomic<int> downloads_{0};
  const std::chrono::steady_clock::time_point started_;
};

}  // namespace cenote::server
