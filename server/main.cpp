// cenote-server: the map as a gRPC service. A vehicle's pipeline feeds it (stereo frames, poses,
// point batches), planners query it, operators snapshot it. See proto/cenote/v1/ for the API and
// server/server_config.h for the settings.
//
//   cenote-server --config config/default.yaml [--listen 127.0.0.1:50051] [--load map.vdb|map.bt]
//                 [--token-file F] [--calibration calib.yaml|DATASET] [--snapshot-dir DIR]
//
// SIGTERM or Ctrl-C: stops taking calls, lets the calls in flight finish (up to a grace period),
// writes the shutdown snapshot and exits 0.
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/security/server_credentials.h>

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
#include "server/services/admin_service.h"
#include "server/cpu/cpu_placement.h"
#include "server/cpu/cpu_scheduling.h"
#include "server/services/ingest_service.h"
#include "server/services/query_service.h"
#include "server/services/updates_service.h"

namespace cenote::server {
namespace {

namespace fs = std::filesystem;

struct Options {
  std::string config, listen, load, token_file, calibration, snapshot_dir, port_file;
  std::string tls_cert, tls_key, tls_client_ca;
  double snapshot_period_s = -1.0;
};

ServerSettings settingsFrom(const Options& o) {
  ServerSettings s = ServerSettings::load(o.config);
  if (!o.listen.empty()) s.server.listen = o.listen;
  if (!o.token_file.empty()) s.server.token_file = o.token_file;
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

std::shared_ptr<grpc::ServerCredentials> credentialsFrom(const Options& o) {
  if (o.tls_cert.empty() && o.tls_key.empty()) {
    if (!o.tls_client_ca.empty()) throw Error("--tls-client-ca needs --tls-cert and --tls-key");
    return grpc::InsecureServerCredentials();
  }
  if (o.tls_cert.empty() || o.tls_key.empty()) throw Error("TLS needs both --tls-cert and --tls-key");
  grpc::SslServerCredentialsOptions tls;
  tls.pem_key_cert_pairs.push_back({readFileBytes(o.tls_key, "TLS key"), readFileBytes(o.tls_cert, "TLS certificate")});
  if (!o.tls_client_ca.empty()) {
    tls.pem_root_certs = readFileBytes(o.tls_client_ca, "TLS client CA");
    tls.client_certificate_request = GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY;
  }
  return grpc::SslServerCredentials(tls);
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

int serve(const Options& o) {
  const sigset_t signals = blockShutdownSignals();
  std::signal(SIGXFSZ, SIG_IGN);  // a file size limit (ulimit -f) fails the snapshot (EFBIG), not the server
  const ServerSettings settings = settingsFrom(o);
  const std::string token = settings.server.token_file.empty() ? ""
                                                               : readTokenFile(settings.server.token_file, "token file");
  CallGuard guard{Authenticator(token)};
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
  UpdatesService updates(host, guard);
  AdminService admin(host, guard, snapshots, ingest);

  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort(settings.server.listen, credentialsFrom(o), &port);
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
  std::cout << "cenote-server listening on " << host_part << ":" << port << (token.empty() ? "" : " (token required)")
            << "; " << cpus.describe() << std::endl;
  if (!o.port_file.empty()) {
    // Appears whole: a test polling for it never reads half.
    writeFileAtomically(o.port_file, std::to_string(port) + "\n", Durability::kFast);
  }

  int signal = 0;
  sigwait(&signals, &signal);
  std::cerr << "cenote-server: " << (signal == SIGTERM ? "SIGTERM" : "SIGINT")
            << ": draining calls, then writing the snapshot" << std::endl;
  if (grpc::HealthCheckServiceInterface* health = server->GetHealthCheckService()) health->Shutdown();  // NOT_SERVING
  updates.shutdown();
  server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(10));
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
  app.add_option("--token-file", o.token_file, "bearer token clients must send (first line of the file)");
  app.add_option("--calibration", o.calibration, "stereo calibration YAML or dataset folder, for Ingest.StreamFrames");
  app.add_option("--snapshot-dir", o.snapshot_dir, "where snapshots are written (default ./snapshots)");
  app.add_option("--snapshot-period", o.snapshot_period_s, "seconds between periodic snapshots (0: none)");
  app.add_option("--port-file", o.port_file, "write the bound port here once serving");
  app.add_option("--tls-cert", o.tls_cert, "PEM server certificate (enables TLS)");
  app.add_option("--tls-key", o.tls_key, "PEM server private key");
  app.add_option("--tls-client-ca", o.tls_client_ca, "PEM CA that client certificates must chain to (mutual TLS)");
  CLI11_PARSE(app, argc, argv);
  try {
    return cenote::server::serve(o);
  } catch (const std::exception& e) {
    std::cerr << "cenote-server: error: " << e.what() << std::endl;
    return 1;
  }
}
