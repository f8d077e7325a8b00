// cenote-server: the map as a gRPC service. A vehicle's pipeline feeds it (stereo frames, poses,
// point batches), planners query it, operators snapshot it. See proto/cenote/v1/ for the API and
// server/server_config.h for the settings.
//
//   cenote-server --config config/default.yaml [--listen 127.0.0.1:50051] [--load map.vdb|map.bt]
//                 [--token-file F [--read-token-file F]] [--calibration calib.yaml|DATASET]
//                 [--snapshot-dir DIR] [--allow-insecure-remote]
//
// SIGTERM or Ctrl-C: stops taking calls, cancels the open streams, lets the other calls in flight
// finish (server.transport.shutdown_grace_s), writes the shutdown snapshot and exits 0.
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/resource_quota.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <pthread.h>

#include "common/atomic_file.h"
#include "common/error.h"
#include "common/text_file.h"
#include "mapping/io/map_io.h"
#include "pipeline/calibration/stereo_calibration.h"
#include "pipeline/dataset/stereo_dataset.h"
#include "proto/grpc_runtime.h"
#include "server/access/access_policy.h"
#include "server/services/admin_service.h"
#include "server/cpu/cpu_placement.h"
#include "server/cpu/cpu_scheduling.h"
#include "server/services/ingest_service.h"
#include "server/services/query_service.h"
#include "server/services/updates_service.h"
#include "server/viewer/host_viewer.h"

namespace cenote::server {
namespace {

namespace fs = std::filesystem;

struct Options {
  std::string config, listen, load, token_file, read_token_file, calibration, snapshot_dir, port_file, viewer_listen;
  TlsFiles tls;
  double snapshot_period_s = -1.0;
  bool allow_insecure_remote = false;
};

ServerSettings settingsFrom(const Options& o) {
  ServerSettings s = ServerSettings::load(o.config);
  if (!o.listen.empty()) s.server.listen = o.listen;
  if (!o.viewer_listen.empty()) s.server.viewer.listen = o.viewer_listen;
  // The viewer's port is as private as the gRPC one: TLS with the server's certificate unless
  // server.viewer names its own.
  if (s.server.viewer.tls_cert_file.empty() && !o.tls.cert.empty()) {
    s.server.viewer.tls_cert_file = o.tls.cert;
    s.server.viewer.tls_key_file = o.tls.key;
  }
  if (!o.token_file.empty()) s.server.token_file = o.token_file;
  if (!o.read_token_file.empty()) s.server.read_token_file = o.read_token_file;
  if (!o.calibration.empty()) s.server.calibration = o.calibration;
  if (!o.snapshot_dir.empty()) s.server.snapshot_dir = o.snapshot_dir;
  if (o.snapshot_period_s >= 0.0) s.server.snapshot_period_s = o.snapshot_period_s;
  throwIfInvalid(s.validate(), "configuration" + (o.config.empty() ? std::string() : " " + o.config));
  return s;
}

std::shared_ptr<const pipeline::Rectifier> rectifierFrom(const std::string& calibration) {
  if (calibration.empty()) return nullptr;
  if (fs::is_directory(calibration)) {
    return std::make_shared<const pipeline::Rectifier>(pipeline::openDataset(calibration)->calibration());
  }
  return std::make_shared<const pipeline::Rectifier>(pipeline::readCalibrationFile(calibration));
}

std::unique_ptr<mapping::OccupancyMap> initialMap(const Options& o, const ServerSettings& s) {
  if (o.load.empty()) return std::make_unique<mapping::OccupancyMap>(s.map);
  if (!fs::exists(o.load)) throw Error("--load " + o.load + ": no such file");
  return mapping::loadMap(o.load, s.map);
}

// Blocks SIGTERM and SIGINT in every thread (call before any thread starts) so that one thread
// can wait for them with sigwait.
sigset_t blockShutdownSignals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  return set;
}

std::string tokenFrom(const std::string& file) { return file.empty() ? "" : readTokenFile(file, "token file"); }

// Refuses to expose the map beyond loopback without a token, or a token without TLS, unless the
// operator said so (--allow-insecure-remote); then says it loudly.
void checkExposure(const Options& o, const ServerSettings& s, const AccessPolicy& access) {
  const std::string problem = exposureProblem(s.server.listen, access.enabled(), !o.tls.cert.empty());
  if (problem.empty()) return;
  if (!o.allow_insecure_remote) throw Error("refusing to start: " + problem);
  std::cerr << "cenote-server: WARNING: " << problem << "\ncenote-server: WARNING: running so because of "
            << "--allow-insecure-remote" << std::endl;
}

// gRPC's resources: a thread quota, keepalive, connection lifetime (server.transport).
void configureTransport(grpc::ServerBuilder& builder, const TransportConfig& t) {
  grpc::ResourceQuota quota("cenote-server");
  quota.SetMaxThreads(t.max_threads);
  builder.SetResourceQuota(quota);
  const auto ms = [](double s) { return static_cast<int>(std::min(s * 1000.0, 2147483647.0)); };
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIME_MS, ms(t.keepalive_time_s));
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, ms(t.keepalive_timeout_s));
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, t.keepalive_without_calls ? 1 : 0);
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MAX_PINGS_WITHOUT_DATA, 0);  // keep pinging an idle link
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS, ms(t.min_client_ping_interval_s));
  if (t.max_connection_idle_s > 0.0)
    builder.AddChannelArgument(GRPC_ARG_MAX_CONNECTION_IDLE_MS, ms(t.max_connection_idle_s));
  if (t.max_connection_age_s > 0.0) builder.AddChannelArgument(GRPC_ARG_MAX_CONNECTION_AGE_MS, ms(t.max_connection_age_s));
  if (t.max_connection_age_grace_s > 0.0) {
    builder.AddChannelArgument(GRPC_ARG_MAX_CONNECTION_AGE_GRACE_MS, ms(t.max_connection_age_grace_s));
  }
}

int serve(const Options& o) {
  const sigset_t signals = blockShutdownSignals();
  std::signal(SIGXFSZ, SIG_IGN);  // a file size limit (ulimit -f) fails the snapshot (EFBIG), not the server
  const ServerSettings settings = settingsFrom(o);
  const auto access = std::make_shared<const AccessPolicy>(tokenFrom(settings.server.token_file),
                                                           tokenFrom(settings.server.read_token_file));
  checkExposure(o, settings, *access);
  CallGuard guard;
  if (!setProcessTimeSlice(settings.server.time_slice_ms)) {
    std::fprintf(stderr, "cenote-server: the kernel refused server.time_slice_ms %g; running with its default\n",
                 settings.server.time_slice_ms);
  }
  const CpuPlacement cpus(settings.server.query_cpus);  // before any thread is pinned
  MapHost host(initialMap(o, settings), settings.server.host);
  Snapshotter snapshots(host, settings.server.snapshot_dir, settings.server.frame_id, settings.server.snapshot_period_s,
                        {o.load, settings.server.limits.max_snapshots, settings.server.limits.max_snapshot_bytes});
  IngestService ingest(host, guard, settings, rectifierFrom(settings.server.calibration), cpus);
  QueryService query(host, guard, settings.server, settings.server.frame_id);
  UpdatesService updates(host, guard, settings.server.limits.max_subscribers);
  AdminService admin(host, guard, snapshots, ingest, settings.server.limits.max_snapshot_downloads);
  viewer::LiveFeed live(settings.server.viewer.max_cloud_points, settings.server.viewer.max_trajectory_poses,
                        settings.server.viewer.image_hz);
  // Viewing is reading: the read-only token lets a viewer in as the operator's does.
  std::vector<std::string> viewer_tokens;
  for (const std::string& file : {settings.server.token_file, settings.server.read_token_file})
    if (!file.empty()) viewer_tokens.push_back(tokenFrom(file));
  const std::unique_ptr<viewer::ViewerServer> viewer = startViewer(settings, host, ingest, live, viewer_tokens);

  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  int port = 0;
  // The token and role are checked as a call's headers arrive, before its message is parsed.
  builder.AddListeningPort(settings.server.listen, serverCredentials(o.tls, access), &port);
  configureTransport(builder, settings.server.transport);
  builder.SetMaxReceiveMessageSize(static_cast<int>(settings.server.limits.max_message_bytes));
  builder.SetMaxSendMessageSize(static_cast<int>(settings.server.limits.max_message_bytes));
  // One completion queue: measured with bench/server_bench on 2 cores, about 30 us of server CPU
  // per single-point query instead of 50 with gRPC's defaults (a queue per core), because fewer
  // threads hand calls to each other. gRPC's sync server ends a thread that finishes a call while
  // max_pollers others poll, and makes one when fewer than min_pollers do: with 8 clients and at
  // most 4 pollers it made about 1300 threads in one server_bench run, with 16 about 100.
  builder.SetSyncServerOption(grpc::ServerBuilder::SyncServerOption::NUM_CQS, settings.server.completion_queues);
  builder.SetSyncServerOption(grpc::ServerBuilder::SyncServerOption::MIN_POLLERS, settings.server.min_pollers);
  builder.SetSyncServerOption(grpc::ServerBuilder::SyncServerOption::MAX_POLLERS, settings.server.max_pollers);
  builder.RegisterService(&ingest);
  builder.RegisterService(&query);
  builder.RegisterService(&updates);
  builder.RegisterService(&admin);
  std::unique_ptr<grpc::Server> server;
  {
    // gRPC's pollers start here and start more of themselves later: all inherit the query CPUs.
    CpuScope pinned(cpus, CpuScope::Side::kQueries);
    server = builder.BuildAndStart();
  }
  if (!server || port == 0) throw Error("cannot listen on " + settings.server.listen + " (address in use or invalid?)");

  const std::string host_part = settings.server.listen.substr(0, settings.server.listen.rfind(':'));
  std::cout << "cenote-server listening on " << host_part << ":" << port << (access->enabled() ? " (token required)" : "")
            << "; " << cpus.describe() << std::endl;
  if (viewer) {
    const std::string viewer_host = settings.server.viewer.listen.substr(0, settings.server.viewer.listen.rfind(':'));
    std::cout << "cenote-server viewer on " << viewer->urls(viewer_host) << std::endl;
  }
  if (!o.port_file.empty()) {
    // Appears whole: a test polling for it never reads half.
    writeFileAtomically(o.port_file, std::to_string(port) + "\n", Durability::kFast);
  }

  int signal = 0;
  sigwait(&signals, &signal);
  std::cerr << "cenote-server: " << (signal == SIGTERM ? "SIGTERM" : "SIGINT")
            << ": cancelling streams, draining calls, then writing the snapshot" << std::endl;
  if (grpc::HealthCheckServiceInterface* health = server->GetHealthCheckService()) health->Shutdown();  // NOT_SERVING
  // Streams never end by themselves: a frame or pose stream is cancelled (its frames already
  // taken still reach the map), a subscription ends with UNAVAILABLE. Unary calls get the grace.
  guard.cancelStreams();
  updates.shutdown();
  if (viewer) viewer->stop();
  server->Shutdown(std::chrono::system_clock::now() +
                   std::chrono::microseconds(static_cast<int64_t>(settings.server.transport.shutdown_grace_s * 1e6)));
  server->Wait();
  snapshots.stop();
  if (settings.server.snapshot_on_shutdown) {
    snapshots.writeLatest();
    std::cerr << "cenote-server: snapshot " << (snapshots.directory() / "map.vdb").string() << std::endl;
  }
  return 0;
}

}  // namespace
}  // namespace cenote::server

int main(int argc, char** argv) {
  cenote::rpc::configureGrpcRuntime();
  cenote::server::Options o;
  CLI::App app{"cenote-server: the volumetric map as a gRPC service (proto/cenote/v1)"};
  app.add_option("--config", o.config, "YAML configuration (sections stereo, fusion, run, map, server)")
      ->check(CLI::ExistingFile);
  app.add_option("--listen", o.listen, "HOST:PORT to listen on (default 127.0.0.1:50051; port 0 picks a free one)");
  app.add_option("--load", o.load, "start from this map (.vdb, .bt or .ot)");
  app.add_option("--token-file", o.token_file, "operator's bearer token clients must send (first line of the file)");
  app.add_option("--read-token-file", o.read_token_file,
                 "read-only bearer token: Query, Updates and Admin.GetStats (needs --token-file)");
  app.add_flag("--allow-insecure-remote", o.allow_insecure_remote,
               "listen beyond loopback without a token, or with one but without TLS (logged as a warning)");
  app.add_option("--calibration", o.calibration, "stereo calibration YAML or dataset folder, for Ingest.StreamFrames");
  app.add_option("--snapshot-dir", o.snapshot_dir, "where snapshots are written (default ./snapshots)");
  app.add_option("--snapshot-period", o.snapshot_period_s, "seconds between periodic snapshots (0: none)");
  app.add_option("--port-file", o.port_file, "write the bound port here once serving");
  app.add_option("--viewer-listen", o.viewer_listen,
                 "HOST:PORT of the live viewer (Foxglove WebSocket and browser page; server.viewer.listen)");
  app.add_option("--tls-cert", o.tls.cert, "PEM server certificate (enables TLS)");
  app.add_option("--tls-key", o.tls.key, "PEM server private key");
  app.add_option("--tls-client-ca", o.tls.client_ca, "PEM CA that client certificates must chain to (mutual TLS)");
  CLI11_PARSE(app, argc, argv);
  try {
    return cenote::server::serve(o);
  } catch (const std::exception& e) {
    std::cerr << "cenote-server: error: " << e.what() << std::endl;
    return 1;
  }
}
