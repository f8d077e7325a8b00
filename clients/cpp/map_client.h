// map_client.h: the C++ client of cenote-server: every call of proto/cenote/v1 (queries, ingest,
// updates, admin) as a typed method taking and returning Eigen types and the plain structs of
// client_types.h. No protobuf or gRPC header beyond the status-code enum is needed to use it.
//
//   cenote::client::MapClient map("127.0.0.1:50051", {.token = "secret"});
//   auto states = map.voxels({{1.0, 0.0, -0.5}});           // std::vector<VoxelResult>
//   auto hits = map.segments({{start, end, 0.3}});          // capsules of radius 0.3 m
//
// Errors: every failed call throws RpcError (code, code name, the server's message).
// Batching: queries with more than ClientOptions::max_batch_items items are split into several
// requests and their answers concatenated in order (each part sees the map at its own version);
// an empty list returns an empty answer without calling the server.
// Units: metres, seconds; frame: the map's world frame.
// Threads: one MapClient may be used from any number of threads at once (gRPC stubs are thread
// safe); an IngestStream or Subscription belongs to the thread(s) that drive it.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "clients/cpp/client_options.h"
#include "clients/cpp/client_types.h"
#include "clients/cpp/rpc_error.h"

namespace grpc {
class Channel;
}

namespace cenote::client {

template <typename Item, typename Ack>
class IngestStream;
// Streams of the Ingest service: items written, one acknowledgement read back per item.
using PointsStream = IngestStream<PointBatch, BatchAck>;
using FramesStream = IngestStream<StereoFrame, FrameAck>;
using PosesStream = IngestStream<PoseStamped, PoseAck>;
class Subscription;

class MapClient {
 public:
  // Connects (lazily, at the first call) to `target`, e.g. "127.0.0.1:50051" or "dns:///host:port".
  // @throws std::invalid_argument for inconsistent TLS options (a client key without a certificate).
  explicit MapClient(const std::string& target, const ClientOptions& options = {});
  // Over an existing channel (shared with other stubs); options' TLS and connection fields are unused.
  MapClient(std::shared_ptr<grpc::Channel> channel, const ClientOptions& options = {});
  ~MapClient();
  MapClient(const MapClient&) = delete;
  MapClient& operator=(const MapClient&) = delete;
  MapClient(MapClient&&) noexcept;
  MapClient& operator=(MapClient&&) noexcept;

  const ClientOptions& options() const;
  std::shared_ptr<grpc::Channel> channel() const;
  // Blocks until connected or timeout_s passed; false on timeout.
  bool waitForConnected(double timeout_s);

  // ---- Queries (Query service). One result per item, in order. ----
  std::vector<VoxelResult> voxels(const std::vector<Eigen::Vector3d>& points_m);
  VoxelResult voxel(const Eigen::Vector3d& point_m) { return voxels({point_m}).front(); }
  std::vector<BoxCounts> boxes(const std::vector<Box>& boxes);
  // Segments (radius 0) and capsules (radius > 0); stop_at_unknown: unknown is not free to pass.
  std::vector<Collision> segments(const std::vector<Segment>& segments, bool stop_at_unknown = false);
  Collision segment(const Segment& segment, bool stop_at_unknown = false) {
    return segments({segment}, stop_at_unknown).front();
  }
  std::vector<Collision> raycast(const std::vector<Ray>& rays, double max_range_m, bool stop_at_unknown = false);
  // Distance to the nearest occupied voxel with its gradient; max_distance_m() of MapInfo beyond.
  std::vector<DistanceResult> distances(const std::vector<Eigen::Vector3d>& points_m);
  std::vector<Frontier> frontiers(const FrontierQuery& query = {});
  // Every known voxel whose centre lies in the box (and the unknown ones with include_unknown).
  ExtractedVoxels extract(const Box& box, bool include_unknown = false);
  MapInfo info();

  // ---- Ingest ----
  // One batch as a unary call: a rejected batch throws RpcError (and the map is unchanged).
  BatchAck integratePoints(const PointBatch& batch);
  // A bidirectional stream of point batches (one BatchAck per batch; a bad batch is rejected in
  // its ack and the stream goes on).
  std::unique_ptr<PointsStream> openPointsStream();
  // Sends every batch over one stream and returns the acks in order (reads acks while writing).
  std::vector<BatchAck> streamPoints(const std::vector<PointBatch>& batches);
  // Stereo frames for the server's own pipeline (it needs --calibration), with back-pressure:
  // write() blocks while the pipeline is busy. Closing the stream finishes the fusion window.
  std::unique_ptr<FramesStream> openFramesStream();
  // Camera poses at VIO rate, matched by timestamp to frames without a pose of their own.
  std::unique_ptr<PosesStream> openPosesStream();

  // ---- Updates ----
  // Calls on_update for every MapUpdate (the full map first) from a background thread, until
  // the Subscription is cancelled or destroyed, or the stream ends.
  std::unique_ptr<Subscription> subscribe(const SubscribeOptions& options, std::function<void(const MapUpdate&)> on_update);
  // The same on the calling thread: returns when on_update returns false (cancelling the stream)
  // or the server ends the stream. @throws RpcError when the stream fails.
  void watch(const SubscribeOptions& options, const std::function<bool(const MapUpdate&)>& on_update);

  // ---- Admin ----
  // Writes the map on the server under its snapshot directory (path relative to it), in the
  // format the extension names. @throws RpcError INVALID_ARGUMENT, before any call, when the
  // extension names no format or another one than `format` (client_types.h).
  SnapshotResult snapshot(const std::string& path, SnapshotFormat format = SnapshotFormat::kFromExtension);
  // Streams the map to a local file (written to `<path>.part`, then renamed) in the format its
  // extension names, as snapshot(): "m.bt" is an OctoMap tree. @return bytes written.
  // @throws RpcError (INVALID_ARGUMENT before any call for a refused extension or format), or
  //         std::runtime_error when the local file cannot be written.
  uint64_t downloadSnapshot(const std::string& local_path, SnapshotFormat format = SnapshotFormat::kFromExtension);
  ChangeResult clearBox(const Box& box);
  ChangeResult clearSphere(const Eigen::Vector3d& centre_m, double radius_m);
  // Forgets everything outside the sphere.
  ChangeResult crop(const Eigen::Vector3d& centre_m, double radius_m);
  ChangeResult reset();
  ServerStats stats();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  template <typename Item, typename Ack>
  friend class IngestStream;
  friend class Subscription;
};

// An open StreamPoints / StreamFrames / StreamPoses call. write() and read() may run on two
// threads (one each) at once. A bad item is rejected in its ack and the stream goes on.
template <typename Item, typename Ack>
class IngestStream {
 public:
  ~IngestStream();  // cancels the call if finish() was not called
  IngestStream(const IngestStream&) = delete;
  IngestStream& operator=(const IngestStream&) = delete;
  // False when the stream is broken (finish() then says why).
  bool write(const Item& item);
  // The next acknowledgement; false when the server has closed its side.
  bool read(Ack& ack);
  // Half-closes, drains the remaining acks into `remaining` (if given) and waits for the status.
  // @throws RpcError when the call failed.
  void finish(std::vector<Ack>* remaining = nullptr);

 private:
  friend class MapClient;
  struct Impl;
  explicit IngestStream(std::unique_ptr<Impl> impl);
  static std::unique_ptr<IngestStream> open(MapClient::Impl& client);  // the call of this Item's stream
  std::unique_ptr<Impl> impl_;
};

extern template class IngestStream<PointBatch, BatchAck>;
extern template class IngestStream<StereoFrame, FrameAck>;
extern template class IngestStream<PoseStamped, PoseAck>;

// A background Subscribe call (MapClient::subscribe).
class Subscription {
 public:
  ~Subscription();  // cancel() and wait
  // Ends the stream; the callback is not called after cancel() returns.
  void cancel();
  // True while the stream is open.
  bool isActive() const;
  // Updates received so far.
  uint64_t updatesReceived() const;
  // Blocks until the stream ends (cancelled or failed). @throws what the callback threw (which
  // ended the stream), or RpcError when the stream failed for any other reason than cancel().
  void wait();

 private:
  friend class MapClient;
  struct Impl;
  explicit Subscription(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace cenote::client
