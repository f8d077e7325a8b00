// End-to-end: the server's life on a vehicle. SIGTERM drains, writes the snapshot and exits 0; a
// restart with --load serves the same map. After kill -9 the last periodic snapshot loads and
// holds the map as it was when written. A configuration with an unknown key is refused at start
// with a message naming the key.
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "mapping/io/map_io.h"
#include "tests/clients/cpp/server_process.h"
#include "tests/server/refused_start.h"
#include "tests/server/server_test_util.h"

namespace cenote::server::test {
namespace {

namespace fs = std::filesystem;
using client::test::ServerProcess;
using client::test::ServerProcessOptions;

void integrate(Stubs& stubs, const v1::PointBatch& batch) {
  auto context = contextWithDeadline();
  v1::BatchAck ack;
  const grpc::Status status = stubs.ingest->IntegratePoints(context.get(), batch, &ack);
  ASSERT_TRUE(status.ok()) << status.error_message();
}

// A server started with --load <dir>/map.vdb serves `before`, voxel for voxel (more than min_known
// voxels known: the premise that there is a map to compare).
void expectLoadedSnapshotServes(const mapping::OccupancyMap& before, const fs::path& dir, uint64_t min_known) {
  ServerProcess restarted(CENOTE_SERVER_BINARY, {.extra_args = {"--load", (dir / "map.vdb").string()}});
  Stubs stubs(restarted.target());
  const MapDifference diff = compareMaps(before, *downloadMap(*stubs.admin, dir.string()));
  EXPECT_GT(diff.known, min_known);
  EXPECT_EQ(diff.different_state, 0u);
  EXPECT_EQ(diff.different_log_odds, 0u);
}

TEST(ServerLifecycle, SigtermWritesASnapshotThatRestoresTheSameMap) {
  const fs::path dir = scratchDir("lifecycle", "sigterm");
  std::unique_ptr<mapping::OccupancyMap> before;
  std::string snapshot;
  {
    ServerProcess server(CENOTE_SERVER_BINARY);
    Stubs stubs(server.target());
    integrate(stubs, wallBatch(2.0, 1.0, 0.02, 1.0));
    integrate(stubs, wallBatch(3.0, 1.5, 0.03, 2.0));
    before = downloadMap(*stubs.admin, dir.string());
    EXPECT_EQ(server.stop(), 0) << server.log();
    snapshot = server.snapshotDirectory() + "/map.vdb";
    ASSERT_TRUE(fs::exists(snapshot)) << server.log();
    fs::copy_file(snapshot, dir / "map.vdb");
  }
  expectLoadedSnapshotServes(*before, dir, 50000u);
  fs::remove_all(dir.parent_path());
}

TEST(ServerLifecycle, AfterKillNineTheLastPeriodicSnapshotLoads) {
  const fs::path dir = scratchDir("lifecycle", "kill9");
  std::unique_ptr<mapping::OccupancyMap> before;
  {
    ServerProcess server(CENOTE_SERVER_BINARY, {.extra_args = {"--snapshot-period", "0.2"}});
    Stubs stubs(server.target());
    integrate(stubs, wallBatch(2.0, 1.0, 0.02, 1.0));
    before = downloadMap(*stubs.admin, dir.string());
    const auto downloaded = std::chrono::steady_clock::now();
    // Wait for a periodic snapshot of this version: one taken after the download (a snapshot
    // taken before the batch was integrated, on a slow start, would hold an older map).
    bool saved = false;
    for (int i = 0; i < 200 && !saved; ++i) {
      const double since_download =  // before the call, so that a snapshot younger than it is later
          std::chrono::duration<double>(std::chrono::steady_clock::now() - downloaded).count();
      auto context = contextWithDeadline();
      v1::Stats stats;
      ASSERT_TRUE(stubs.admin->GetStats(context.get(), v1::StatsRequest(), &stats).ok());
      saved = stats.last_snapshot_age_s() >= 0.0 && stats.last_snapshot_age_s() < since_download;
      if (!saved) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    ASSERT_TRUE(saved) << server.log();
    ASSERT_EQ(kill(server.pid(), SIGKILL), 0);
    EXPECT_EQ(server.stop(), 128 + SIGKILL);
    fs::copy_file(server.snapshotDirectory() + "/map.vdb", dir / "map.vdb");
  }
  expectLoadedSnapshotServes(*before, dir, 20000u);
  fs::remove_all(dir.parent_path());
}

TEST(ServerLifecycle, BadStartupInputIsRefusedWithAMessageNamingIt) {
  const fs::path dir = scratchDir("lifecycle", "config");
  std::ofstream(dir / "typo.yaml") << "server:\n  listne: 127.0.0.1:1\n";
  expectRefusedToStart(dir, "--config " + (dir / "typo.yaml").string(), {"server.listne"});

  std::ofstream(dir / "range.yaml")
      << "map:\n  voxel_size_m: -1\nserver:\n  max_frame_streams: 0\n  time_slice_ms: 0.05\n  query_cpus: -1\n";
  expectRefusedToStart(dir, "--config " + (dir / "range.yaml").string(),
                       {"map.voxel_size_m", "server.max_frame_streams", "server.time_slice_ms", "server.query_cpus"});
  expectRefusedToStart(dir, "--listen 127.0.0.1:0 --load " + (dir / "missing.vdb").string(), {"missing.vdb: no such file"});
  expectRefusedToStart(dir, "--listen 127.0.0.1:0 --token-file " + (dir / "no-token").string(),
                       {"no-token cannot be read"});
  fs::remove_all(dir.parent_path());
}

TEST(ServerLifecycle, GrpcThreadsRunOnTheQueryCpuAndTheMapOnAll) {
  const std::string all = cpusOfThisProcess();
  if (all.find_first_of("-,") == std::string::npos) GTEST_SKIP() << "the process may use one CPU only (" << all << ")";
  ServerProcess server(CENOTE_SERVER_BINARY);  // default configuration: query_cpus 1
  Stubs stubs(server.target());
  integrate(stubs, wallBatch(2.0, 1.0, 0.02, 1.0));  // the writer's OpenMP team exists now
  EXPECT_NE(server.log().find("gRPC threads on CPU"), std::string::npos) << server.log();
  const std::string last = all.substr(all.find_last_of("-,") + 1);
  int grpc_threads = 0, own_threads = 0;
  for (const ThreadInfo& thread : threadsOf(server.pid())) {
    if (thread.name == "grpcpp_sync_ser") {  // gRPC's pollers, where the handlers run
      ++grpc_threads;
      EXPECT_EQ(thread.cpus, last);
    } else if (thread.name == "cenote-server") {  // main, map writer and its OpenMP team, derived, snapshots
      ++own_threads;
      EXPECT_EQ(thread.cpus, all);
    }
  }
  EXPECT_GE(grpc_threads, 2);  // server.min_pollers
  EXPECT_GE(own_threads, 4);
}

}  // namespace
}  // namespace cenote::server::test
