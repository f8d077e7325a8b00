// map_client.cpp: MapClient's unary calls (queries, IntegratePoints, admin) and its channel.
#include "clients/cpp/map_client.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "clients/cpp/batching.h"
#include "clients/cpp/detail/client_impl.h"
#include "clients/cpp/detail/wire.h"
#include "common/error.h"
#include "mapping/io/map_file_format.h"
#include "proto/grpc_runtime.h"

namespace cenote::client {

using detail::throwIfFailed;

namespace {

std::shared_ptr<grpc::Channel> makeChannel(const std::string& target, const ClientOptions& options) {
  rpc::configureGrpcRuntime();
  if (options.tls_client_cert_pem.empty() != options.tls_client_key_pem.empty()) {
    throw std::invalid_argument("client TLS: give both a client certificate and its key, or neither");
  }
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(options.max_message_bytes);
  args.SetMaxSendMessageSize(options.max_message_bytes);
  if (options.own_connection) args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
  std::shared_ptr<grpc::ChannelCredentials> credentials;
  if (options.use_tls) {
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = options.tls_root_cert_pem;
    ssl.pem_cert_chain = options.tls_client_cert_pem;
    ssl.pem_private_key = options.tls_client_key_pem;
    credentials = grpc::SslCredentials(ssl);
  } else {
    credentials = grpc::InsecureChannelCredentials();
  }
  return grpc::CreateCustomChannel(target, credentials, args);
}

// A reply that does not match its request is the server's fault, reported like a failed call.
void checkCount(const char* what, size_t got, size_t want) {
  if (got != want) {
    throw RpcError(grpc::StatusCode::INTERNAL, std::string("server replied with ") + std::to_string(got) + " " + what +
                                                   " for " + std::to_string(want) + " items");
  }
}

// The fill of a batched point query: the batch's points as flat x, y, z into request.xyz.
template <typename Request>
auto points(const std::vector<Eigen::Vector3d>& points_m, Request& request) {
  return [&points_m, &request](size_t begin, size_t end) {
    request.clear_xyz();
    detail::appendFlat(points_m, begin, end, request.mutable_xyz());
  };
}

// The fill of a batched query of client values: the batch's items through detail::toWire into the
// request's repeated field that `clear` empties and `add` appends to.
template <typename Item, typename Request, typename Wire>
auto wireItems(const std::vector<Item>& items, Request& request, void (Request::*clear)(), Wire* (Request::*add)()) {
  return [&items, &request, clear, add](size_t begin, size_t end) {
    (request.*clear)();
    for (size_t i = begin; i < end; ++i) detail::toWire(items[i], (request.*add)());
  };
}

// The take of a batched segment or ray query: one collision per item, appended to out.
auto collisions(const v1::CollisionsReply& reply, std::vector<Collision>& out) {
  return [&reply, &out](size_t begin, size_t end) {
    checkCount("collisions", static_cast<size_t>(reply.results_size()), end - begin);
    for (const auto& result : reply.results()) out.push_back(detail::fromWire(result));
  };
}

}  // namespace

MapClient::MapClient(const std::string& target, const ClientOptions& options)
    : impl_(std::make_unique<Impl>(makeChannel(target, options), options)) {}

MapClient::MapClient(std::shared_ptr<grpc::Channel> channel, const ClientOptions& options)
    : impl_(std::make_unique<Impl>(std::move(channel), options)) {
  rpc::configureGrpcRuntime();
}

MapClient::~MapClient() = default;
MapClient::MapClient(MapClient&&) noexcept = default;
MapClient& MapClient::operator=(MapClient&&) noexcept = default;

const ClientOptions& MapClient::options() const { return impl_->options; }
std::shared_ptr<grpc::Channel> MapClient::channel() const { return impl_->channel; }

bool MapClient::waitForConnected(double timeout_s) {
  return impl_->channel->WaitForConnected(std::chrono::system_clock::now() +
                                          std::chrono::microseconds(static_cast<int64_t>(timeout_s * 1e6)));
}

// ---- Queries ----

std::vector<VoxelResult> MapClient::voxels(const std::vector<Eigen::Vector3d>& points_m) {
  std::vector<VoxelResult> out;
  out.reserve(points_m.size());
  v1::VoxelsRequest request;
  v1::VoxelsReply reply;
  impl_->batched(points_m.size(), &v1::Query::Stub::GetVoxels, request, reply, points(points_m, request),
                 [&](size_t begin, size_t end) {
                   checkCount("states", static_cast<size_t>(reply.states_size()), end - begin);
                   checkCount("probabilities", static_cast<size_t>(reply.probabilities_size()), end - begin);
                   for (int i = 0; i < reply.states_size(); ++i) {
                     out.push_back({static_cast<VoxelState>(reply.states(i)), reply.probabilities(i)});
                   }
                 });
  return out;
}

std::vector<BoxCounts> MapClient::boxes(const std::vector<Box>& boxes) {
  std::vector<BoxCounts> out;
  out.reserve(boxes.size());
  v1::BoxesRequest request;
  v1::BoxesReply reply;
  impl_->batched(boxes.size(), &v1::Query::Stub::GetBoxes, request, reply,
                 wireItems(boxes, request, &v1::BoxesRequest::clear_boxes, &v1::BoxesRequest::add_boxes),
                 [&](size_t begin, size_t end) {
                   checkCount("box counts", static_cast<size_t>(reply.counts_size()), end - begin);
                   for (const auto& counts : reply.counts()) out.push_back(detail::fromWire(counts));
                 });
  return out;
}

std::vector<Collision> MapClient::segments(const std::vector<Segment>& segments, bool stop_at_unknown) {
  std::vector<Collision> out;
  out.reserve(segments.size());
  v1::SegmentsRequest request;
  v1::CollisionsReply reply;
  request.set_stop_at_unknown(stop_at_unknown);
  impl_->batched(segments.size(), &v1::Query::Stub::CheckSegments, request, reply,
                 wireItems(segments, request, &v1::SegmentsRequest::clear_segments, &v1::SegmentsRequest::add_segments),
                 collisions(reply, out));
  return out;
}

std::vector<Collision> MapClient::raycast(const std::vector<Ray>& rays, double max_range_m, bool stop_at_unknown) {
  std::vector<Collision> out;
  out.reserve(rays.size());
  v1::RaycastRequest request;
  v1::CollisionsReply reply;
  request.set_max_range_m(max_range_m);
  request.set_stop_at_unknown(stop_at_unknown);
  impl_->batched(rays.size(), &v1::Query::Stub::Raycast, request, reply,
                 wireItems(rays, request, &v1::RaycastRequest::clear_rays, &v1::RaycastRequest::add_rays),
                 collisions(reply, out));
  return out;
}

std::vector<DistanceResult> MapClient::distances(const std::vector<Eigen::Vector3d>& points_m) {
  std::vector<DistanceResult> out;
  out.reserve(points_m.size());
  v1::DistancesRequest request;
  v1::DistancesReply reply;
  impl_->batched(
      points_m.size(), &v1::Query::Stub::GetDistances, request, reply, points(points_m, request),
      [&](size_t begin, size_t end) {
        const size_t n = end - begin;
        checkCount("distances", static_cast<size_t>(reply.distances_m_size()), n);
        checkCount("gradient components", static_cast<size_t>(reply.gradients_size()), 3 * n);
        checkCount("within_max flags", static_cast<size_t>(reply.within_max_size()), n);
        for (int i = 0; i < reply.distances_m_size(); ++i) {
          out.push_back({reply.distances_m(i),
                         Eigen::Vector3d(reply.gradients(3 * i), reply.gradients(3 * i + 1), reply.gradients(3 * i + 2)),
                         reply.within_max(i)});
        }
      });
  return out;
}

std::vector<Frontier> MapClient::frontiers(const FrontierQuery& query) {
  v1::FrontiersRequest request;
  v1::FrontiersReply reply;
  detail::toWire(query.position_m, request.mutable_position());
  if (!query.region.isEmpty()) detail::toWire(query.region, request.mutable_region());
  request.set_max_clusters(query.max_clusters);
  impl_->unary(*impl_->query, &v1::Query::Stub::GetFrontiers, request, reply);
  std::vector<Frontier> out;
  out.reserve(static_cast<size_t>(reply.frontiers_size()));
  for (const auto& f : reply.frontiers()) out.push_back(detail::fromWire(f));
  return out;
}

ExtractedVoxels MapClient::extract(const Box& box, bool include_unknown) {
  v1::ExtractRequest request;
  v1::ExtractReply reply;
  detail::toWire(box, request.mutable_box());
  request.set_include_unknown(include_unknown);
  impl_->unary(*impl_->query, &v1::Query::Stub::ExtractVoxels, request, reply);
  const size_t n = static_cast<size_t>(reply.states_size());
  checkCount("voxel indices", static_cast<size_t>(reply.ijk_size()), 3 * n);
  checkCount("probabilities", static_cast<size_t>(reply.probabilities_size()), n);
  ExtractedVoxels out;
  out.voxel_size_m = reply.voxel_size_m();
  out.map_version = reply.map_version();
  out.ijk.resize(n);
  out.states.resize(n);
  out.probabilities.assign(reply.probabilities().begin(), reply.probabilities().end());
  out.rgb.assign(n, {0, 0, 0});
  const std::string& rgb = reply.rgb();
  for (size_t i = 0; i < n; ++i) {
    const int k = static_cast<int>(3 * i);
    out.ijk[i] = Eigen::Vector3i(reply.ijk(k), reply.ijk(k + 1), reply.ijk(k + 2));
    out.states[i] = static_cast<VoxelState>(reply.states(static_cast<int>(i)));
    if (rgb.size() >= 3 * (i + 1)) {
      for (size_t c = 0; c < 3; ++c) out.rgb[i][c] = static_cast<uint8_t>(rgb[3 * i + c]);
    }
  }
  return out;
}

MapInfo MapClient::info() {
  v1::MapInfo reply;
  impl_->unary(*impl_->query, &v1::Query::Stub::GetMapInfo, v1::MapInfoRequest(), reply);
  return detail::fromWire(reply);
}

// ---- Ingest ----

BatchAck MapClient::integratePoints(const PointBatch& batch) {
  if (!batch.rgb.empty() && batch.rgb.size() != batch.points_m.size()) {
    throw std::invalid_argument("integratePoints: " + std::to_string(batch.rgb.size()) + " colours for " +
                                std::to_string(batch.points_m.size()) + " points");
  }
  v1::PointBatch request;
  v1::BatchAck reply;
  detail::toWire(batch, &request);
  impl_->unary(*impl_->ingest, &v1::Ingest::Stub::IntegratePoints, request, reply);
  return detail::fromWire(reply);
}

// ---- Admin ----

namespace {

static_assert(static_cast<int>(SnapshotFormat::kPointsPcd) == v1::SNAPSHOT_FORMAT_POINTS_PCD &&
                  static_cast<int>(SnapshotFormat::kPointsPcd) == static_cast<int>(mapping::MapFileFormat::kPointsPcd),
              "SnapshotFormat, admin.proto's SnapshotFormat and mapping::MapFileFormat share their numbers");

// The format of `path` by mapping/io/map_file_format.h's rule, as the server would decide it.
SnapshotFormat resolveFormat(const std::string& path, SnapshotFormat format) {
  try {
    return static_cast<SnapshotFormat>(mapping::resolveMapFileFormat(path, static_cast<mapping::MapFileFormat>(format)));
  } catch (const Error& e) {
    throw RpcError(grpc::StatusCode::INVALID_ARGUMENT, e.what());
  }
}

}  // namespace

SnapshotResult MapClient::snapshot(const std::string& path, SnapshotFormat format) {
  v1::SnapshotRequest request;
  v1::SnapshotReply reply;
  request.set_path(path);
  request.set_format(static_cast<v1::SnapshotFormat>(resolveFormat(path, format)));
  impl_->unary(*impl_->admin, &v1::Admin::Stub::Snapshot, request, reply);
  return {reply.path(), reply.bytes(), reply.map_version()};
}

uint64_t MapClient::downloadSnapshot(const std::string& local_path, SnapshotFormat format) {
  v1::SnapshotRequest request;
  request.set_format(static_cast<v1::SnapshotFormat>(resolveFormat(local_path, format)));
  request.set_path(std::filesystem::path(local_path).filename().string());  // the server checks it too
  grpc::ClientContext context;
  // A whole map can take far longer than one query: ten deadlines.
  impl_->prepare(context, 10.0 * impl_->options.deadline_s);
  std::unique_ptr<grpc::ClientReader<v1::FileChunk>> reader = impl_->admin->DownloadSnapshot(&context, request);
  const std::string part = local_path + ".part";
  std::ofstream file(part, std::ios::binary | std::ios::trunc);
  if (!file) throw std::runtime_error("downloadSnapshot: cannot write " + part);
  v1::FileChunk chunk;
  uint64_t written = 0;
  uint64_t total = 0;
  while (reader->Read(&chunk)) {
    if (chunk.offset() != written) {
      context.TryCancel();
      reader->Finish();
      std::filesystem::remove(part);
      throw RpcError(grpc::StatusCode::DATA_LOSS, "snapshot chunk at offset " + std::to_string(chunk.offset()) +
                                                      ", expected " + std::to_string(written));
    }
    file.write(chunk.data().data(), static_cast<std::streamsize>(chunk.data().size()));
    written += chunk.data().size();
    total = chunk.total_bytes();
  }
  const grpc::Status status = reader->Finish();
  file.close();
  if (!status.ok()) {
    std::filesystem::remove(part);
    throwIfFailed(status);
  }
  if (!file) throw std::runtime_error("downloadSnapshot: writing " + part + " failed (disk full?)");
  if (total != 0 && written != total) {
    std::filesystem::remove(part);
    throw RpcError(grpc::StatusCode::DATA_LOSS,
                   "snapshot ended after " + std::to_string(written) + " of " + std::to_string(total) + " bytes");
  }
  std::filesystem::rename(part, local_path);
  return written;
}

ChangeResult MapClient::clearBox(const Box& box) {
  v1::ClearBoxRequest request;
  v1::ChangeReply reply;
  detail::toWire(box, request.mutable_box());
  impl_->unary(*impl_->admin, &v1::Admin::Stub::ClearBox, request, reply);
  return detail::fromWire(reply);
}

namespace {

// ClearSphere and Crop: a sphere in, the change out. `impl` is MapClient's Impl.
template <typename ClientImpl, typename Request>
ChangeResult sphereChange(const ClientImpl& impl,
                          grpc::Status (v1::Admin::Stub::*method)(grpc::ClientContext*, const Request&, v1::ChangeReply*),
                          const Eigen::Vector3d& centre_m, double radius_m) {
  Request request;
  v1::ChangeReply reply;
  detail::toWire(centre_m, request.mutable_centre());
  request.set_radius_m(radius_m);
  impl.unary(*impl.admin, method, request, reply);
  return detail::fromWire(reply);
}

}  // namespace

ChangeResult MapClient::clearSphere(const Eigen::Vector3d& centre_m, double radius_m) {
  return sphereChange(*impl_, &v1::Admin::Stub::ClearSphere, centre_m, radius_m);
}

ChangeResult MapClient::crop(const Eigen::Vector3d& centre_m, double radius_m) {
  return sphereChange(*impl_, &v1::Admin::Stub::Crop, centre_m, radius_m);
}

ChangeResult MapClient::reset() {
  v1::ChangeReply reply;
  impl_->unary(*impl_->admin, &v1::Admin::Stub::Reset, v1::ResetRequest(), reply);
  return detail::fromWire(reply);
}

ServerStats MapClient::stats() {
  v1::Stats reply;
  impl_->unary(*impl_->admin, &v1::Admin::Stub::GetStats, v1::StatsRequest(), reply);
  return detail::fromWire(reply);
}

}  // namespace cenote::client
