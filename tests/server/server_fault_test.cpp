// End-to-end faults: a real server under 15 Hz ingest and 8 query clients is killed with SIGKILL
// at random points (fixed seed) three times in a row; after each kill the last periodic snapshot
// loads, and the restarted server (--load) serves exactly that map. On a full disk (a file-size
// limit, RLIMIT_FSIZE) a snapshot fails with RESOURCE_EXHAUSTED naming the file, and the previous
// snapshot stays whole.
#include <gtest/gtest.h>
#include <signal.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <random>
#include <thread>

#include "mapping/io/map_io.h"
#include "tests/clients/cpp/server_process.h"
#include "tests/server/server_test_util.h"

namespace cenote::server::test {
namespace {

namespace fs = std::filesystem;
using client::test::ServerProcess;
using client::test::ServerProcessOptions;

// Load on the server while the test waits: one thread integrating a new wall every 1/15 s, and 8
// planners querying points and segments. Counts the calls that failed with anything but the
// server going away.
class Load {
 public:
  explicit Load(const std::string& target) {
    threads_.emplace_back([this, target] {
      Stubs stubs(target);
      for (int i = 0; !stop_; ++i) {
        auto context = contextWithDeadline(10.0);
        v1::BatchAck ack;
        const double x = 2.0 + 0.05 * (i % 40);
        count(stubs.ingest->IntegratePoints(context.get(), wallBatch(x, 1.0, 0.05, 1.0 + i), &ack));
        std::this_thread::sleep_for(std::chrono::milliseconds(66));
      }
    });
    for (int q = 0; q < 8; ++q) {
      threads_.emplace_back([this, target, q] {
        Stubs stubs(target);
        std::mt19937 rng(q);
        std::uniform_real_distribution<double> u(-1.0, 4.0);
        while (!stop_) {
          v1::SegmentsRequest request;
          for (int s = 0; s < 16; ++s) {
            v1::Segment* segment = request.add_segments();
            segment->mutable_start()->set_x(0.0);
            segment->mutable_end()->set_x(u(rng));
            segment->mutable_end()->set_y(u(rng) - 1.5);
            segment->mutable_end()->set_z(u(rng) - 1.5);
          }
          auto context = contextWithDeadline(10.0);
          v1::CollisionsReply reply;
          count(stubs.query->CheckSegments(context.get(), request, &reply));
          std::this_thread::sleep_for(std::chrono::milliseconds(5));
        }
      });
    }
  }
  ~Load() {
    stop_ = true;
    for (auto& t : threads_) t.join();
  }
  int unexpected() const { return unexpected_; }

 private:
  void count(const grpc::Status& s) {
    if (!s.ok() && s.error_code() != grpc::StatusCode::UNAVAILABLE) ++unexpected_;
  }
  std::atomic<bool> stop_{false};
  std::atomic<int> unexpected_{0};
  std::vector<std::thread> threads_;
};

TEST(ServerFaults, AfterEachOfThreeKillsUnderLoadTheLastSnapshotLoadsAndIsServedWhole) {
  const fs::path dir = scratchDir("fault", "kill");
  std::mt19937 rng(16);
  std::uniform_int_distribution<int> kill_after_ms(300, 1500);
  std::string load;  // the snapshot the next round starts from
  uint64_t known_before = 0;
  for (int round = 0; round < 3; ++round) {
    std::vector<std::string> args = {"--snapshot-period", "0.1"};
    if (!load.empty()) args.insert(args.end(), {"--load", load});
    ServerProcess server(CENOTE_SERVER_BINARY, {.token = "", .listen = "127.0.0.1:0", .extra_args = args});
    Stubs stubs(server.target());
    if (!load.empty()) {
      // The restarted server serves the snapshot it loaded, voxel for voxel.
      const auto loaded = mapping::loadMap(load);
      const MapDifference diff = compareMaps(*loaded, *downloadMap(*stubs.admin, dir.string()));
      EXPECT_EQ(diff.known, known_before) << "round " << round;
      EXPECT_EQ(diff.different_state, 0u) << "round " << round;
      EXPECT_EQ(diff.different_log_odds, 0u) << "round " << round;
    }
    int unexpected = 0;
    {
      Load busy(server.target());
      std::this_thread::sleep_for(std::chrono::milliseconds(kill_after_ms(rng)));
      // Wait for at least one periodic snapshot of this round's changes, then kill at a random point.
      for (int i = 0; i < 100; ++i) {
        auto context = contextWithDeadline();
        v1::Stats stats;
        if (stubs.admin->GetStats(context.get(), v1::StatsRequest(), &stats).ok() && stats.last_snapshot_age_s() >= 0)
          break;
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(kill_after_ms(rng) / 10));
      ASSERT_EQ(kill(server.pid(), SIGKILL), 0);
      EXPECT_EQ(server.stop(), 128 + SIGKILL);
      unexpected = busy.unexpected();
    }
    EXPECT_EQ(unexpected, 0) << "round " << round << ": calls that failed other than by the kill";
    const fs::path snapshot = fs::path(server.snapshotDirectory()) / "map.vdb";
    ASSERT_TRUE(fs::exists(snapshot)) << "round " << round << "\n" << server.log();
    load = (dir / ("round" + std::to_string(round) + ".vdb")).string();
    fs::copy_file(snapshot, load, fs::copy_options::overwrite_existing);
    const auto map = mapping::loadMap(load);  // whole: a torn file would not load
    known_before = map->stats().occupied + map->stats().free;
    EXPECT_GT(known_before, 1000u) << "round " << round;
  }
  fs::remove_all(dir.parent_path());
}

grpc::Status snapshot(Stubs& stubs, const std::string& path) {
  auto context = contextWithDeadline();
  v1::SnapshotRequest request;
  request.set_path(path);
  v1::SnapshotReply reply;
  return stubs.admin->Snapshot(context.get(), request, &reply);
}

TEST(ServerFaults, OnAFullDiskASnapshotFailsNamingTheFileAndThePreviousOneStaysWhole) {
  const fs::path dir = scratchDir("fault", "full");
  // The server with a file-size limit of 256 KiB (RLIMIT_FSIZE) and SIGXFSZ ignored, so that a
  // write beyond it fails with EFBIG as a full disk's does with ENOSPC.
  const fs::path wrapper = dir / "limited-server.sh";
  std::ofstream(wrapper) << "#!/bin/bash\nulimit -f 256\ntrap '' XFSZ\nexec " << CENOTE_SERVER_BINARY << " \"$@\"\n";
  fs::permissions(wrapper, fs::perms::owner_all);
  ServerProcess server(
      wrapper.string(),
      {.extra_args = {"--config", writeConfig(dir, "server:\n  snapshot_period_s: 0\n  snapshot_on_shutdown: false\n")}});
  Stubs stubs(server.target());

  auto context = contextWithDeadline();
  v1::BatchAck ack;
  ASSERT_TRUE(stubs.ingest->IntegratePoints(context.get(), wallBatch(2.0, 0.5, 0.05, 1.0), &ack).ok());
  ASSERT_TRUE(snapshot(stubs, "map.vdb").ok());
  const fs::path file = fs::path(server.snapshotDirectory()) / "map.vdb";
  const auto small = mapping::loadMap(file.string());
  ASSERT_LT(fs::file_size(file), 256u << 10);

  for (int i = 0; i < 6; ++i) {
    auto more = contextWithDeadline();
    ASSERT_TRUE(stubs.ingest->IntegratePoints(more.get(), wallBatch(3.0 + i, 2.0 + i, 0.02, 2.0 + i), &ack).ok());
  }
  const grpc::Status full = snapshot(stubs, "map.vdb");
  EXPECT_EQ(full.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << full.error_message();
  EXPECT_NE(full.error_message().find("cannot write " + file.string()), std::string::npos) << full.error_message();

  // The previous snapshot is the one on disk, whole, and no temporary file is left beside it.
  const MapDifference diff = compareMaps(*small, *mapping::loadMap(file.string()));
  EXPECT_GT(diff.known, 0u);
  EXPECT_EQ(diff.different_state, 0u);
  EXPECT_EQ(diff.different_log_odds, 0u);
  for (const auto& entry : fs::directory_iterator(server.snapshotDirectory())) {
    EXPECT_EQ(entry.path().filename(), "map.vdb");
  }
  EXPECT_EQ(server.stop(), 0) << server.log();
  fs::remove_all(dir.parent_path());
}

}  // namespace
}  // namespace cenote::server::test
