// End-to-end faults of snapshots on a real server and real files:
//  - restarted without --load in a snapshot directory that holds the previous session's map.vdb,
//    it keeps that file (renamed, said so at start-up) and writes its own; with --load it continues;
//  - killed with SIGKILL K times at pseudo-random points under ingest and queries, each restart with
//    --load serves exactly the last snapshot, which always loads;
//  - beyond a file size limit (RLIMIT_FSIZE, as `ulimit -f` sets), a snapshot fails with
//    RESOURCE_EXHAUSTED, the previous file stays intact, and the server goes on.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <atomic>
#include <cstring>
#include <iterator>
#include <random>
#include <thread>

#include "mapping/io/map_io.h"

#include "tests/server/server_test_util.h"

namespace cenote::server::test {
namespace {

namespace fs = std::filesystem;

std::string contents(const fs::path& p);

// cenote-server on loopback with `--snapshot-dir dir` (ServerProcess picks a directory of its own),
// its log in dir/../<name>.log; stop() sends SIGTERM and returns the exit status.
class Server {
 public:
  Server(const fs::path& dir, const std::string& name, std::vector<std::string> extra)
      : log_(dir.parent_path() / (name + ".log")) {
    const fs::path port_file = dir.parent_path() / (name + ".port");
    fs::remove(port_file);
    std::vector<std::string> args = {CENOTE_SERVER_BINARY, "--listen",       "127.0.0.1:0", "--port-file",
                                     port_file.string(),   "--snapshot-dir", dir.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    pid_ = fork();
    if (pid_ == 0) {
      const int fd = open(log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(fd, 1);
      dup2(fd, 2);
      std::vector<char*> argv;
      for (std::string& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      execv(argv[0], argv.data());
      _exit(127);
    }
    for (int i = 0; i < 600 && port_ == 0; ++i) {
      const std::string text = contents(port_file);
      if (!text.empty() && text.back() == '\n') port_ = std::atoi(text.c_str());
      if (port_ == 0) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
  ~Server() {
    if (pid_ > 0) stop();
  }
  std::string target() const { return "127.0.0.1:" + std::to_string(port_); }
  bool listening() const { return port_ > 0; }
  std::string log() const { return contents(log_); }
  pid_t pid() const { return pid_; }
  void kill9() {
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
    pid_ = -1;
  }
  int stop() {
    kill(pid_, SIGTERM);
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }

 private:
  fs::path log_;
  pid_t pid_ = -1;
  int port_ = 0;
};

std::string contents(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::vector<fs::path> rotated(const fs::path& dir) {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("map.", 0) == 0 && name != "map.vdb" && name.find(".tmp-") == std::string::npos) out.push_back(e.path());
  }
  return out;
}

TEST(ServerSnapshotFaults, RestartWithoutLoadKeepsThePreviousMapVdb) {
  const fs::path dir = fs::temp_directory_path() / ("cenote-rotation-" + std::to_string(getpid())) / "snapshots";
  fs::remove_all(dir.parent_path());
  fs::create_directories(dir);
  std::string first;
  {  // the first session: a wall, written at SIGTERM
    Server server(dir, "first", {});
    ASSERT_TRUE(server.listening()) << server.log();
    Stubs stubs(server.target());
    auto context = contextWithDeadline();
    v1::BatchAck ack;
    ASSERT_TRUE(stubs.ingest->IntegratePoints(context.get(), wallBatch(2.0, 0.5, 0.05, 1.0), &ack).ok());
    ASSERT_EQ(server.stop(), 0) << server.log();
    first = contents(dir / "map.vdb");
    ASSERT_FALSE(first.empty());
  }
  {  // restarted without --load: an empty map, and the first session's file kept
    Server server(dir, "second", {});
    ASSERT_TRUE(server.listening()) << server.log();
    const std::vector<fs::path> kept = rotated(dir);
    ASSERT_EQ(kept.size(), 1u) << server.log();
    EXPECT_TRUE(contents(kept[0]) == first);
    EXPECT_NE(server.log().find("map.vdb was not loaded (no --load): kept as " + kept[0].filename().string()),
              std::string::npos)
        << server.log();
    Stubs stubs(server.target());
    auto context = contextWithDeadline();
    v1::BatchAck ack;  // something to write at SIGTERM
    ASSERT_TRUE(stubs.ingest->IntegratePoints(context.get(), wallBatch(3.0, 0.5, 0.05, 1.0), &ack).ok());
    ASSERT_EQ(server.stop(), 0) << server.log();
    EXPECT_TRUE(contents(kept[0]) == first);
    EXPECT_TRUE(contents(dir / "map.vdb") != first);
  }
  const std::string second = contents(dir / "map.vdb");
  {  // with --load of it: continued, nothing more rotated
    Server server(dir, "third", {"--load", (dir / "map.vdb").string()});
    ASSERT_TRUE(server.listening()) << server.log();
    EXPECT_EQ(rotated(dir).size(), 1u) << server.log();
    EXPECT_TRUE(contents(dir / "map.vdb") == second);
    ASSERT_EQ(server.stop(), 0) << server.log();
  }
  fs::remove_all(dir.parent_path());
}

void integrate(Stubs& stubs, const v1::PointBatch& batch) {
  auto context = contextWithDeadline();
  v1::BatchAck ack;
  const grpc::Status status = stubs.ingest->IntegratePoints(context.get(), batch, &ack);
  ASSERT_TRUE(status.ok()) << status.error_message();
}

// Temporary files (common/atomic_file.h: <stem>.tmp-<pid><ext>) of any process but `live`.
bool hasTemporaries(const fs::path& dir, pid_t live = -1) {
  const std::string own = ".tmp-" + std::to_string(live) + ".";
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.find(".tmp-") != std::string::npos && name.find(own) == std::string::npos) return true;
  }
  return false;
}

// 15 Hz ingest of walls and 4 query clients, killed with SIGKILL at a pseudo-random point (fixed
// seed) 3 times; snapshots every 0.1 s. After each kill map.vdb loads, and the server restarted with
// --load serves it voxel for voxel.
TEST(ServerSnapshotFaults, AfterEachSigkillTheRestartServesTheLastSnapshot) {
  const fs::path dir = fs::temp_directory_path() / ("cenote-sigkill-" + std::to_string(getpid())) / "snapshots";
  fs::remove_all(dir.parent_path());
  fs::create_directories(dir);
  std::mt19937 rng(16);
  constexpr int kKills = 3;
  for (int session = 0; session <= kKills; ++session) {
    std::vector<std::string> args = {"--snapshot-period", "0.1"};
    std::unique_ptr<mapping::OccupancyMap> expected;
    if (session > 0) {
      ASSERT_TRUE(fs::exists(dir / "map.vdb")) << "session " << session;
      fs::copy_file(dir / "map.vdb", dir.parent_path() / "expected.vdb", fs::copy_options::overwrite_existing);
      expected = mapping::loadMap((dir.parent_path() / "expected.vdb").string());  // throws if corrupt
      args.insert(args.end(), {"--load", (dir / "map.vdb").string()});
    }
    Server server(dir, "session" + std::to_string(session), args);
    ASSERT_TRUE(server.listening()) << server.log();
    EXPECT_FALSE(hasTemporaries(dir, server.pid())) << "session " << session << ": a killed write's temporary file is left";
    Stubs stubs(server.target());
    if (expected) {
      const auto served = downloadMap(*stubs.admin, dir.parent_path().string());
      const MapDifference diff = compareMaps(*expected, *served);
      EXPECT_GT(diff.known, 0u) << "session " << session;
      EXPECT_EQ(diff.different_state, 0u) << "session " << session;
      EXPECT_EQ(diff.different_log_odds, 0u) << "session " << session;
    }
    if (session == kKills) {
      EXPECT_EQ(server.stop(), 0) << server.log();
      break;
    }
    // A snapshot of this session's first wall before the kill timer starts: map.vdb exists.
    integrate(stubs, wallBatch(2.0 + session, 1.0, 0.05, 1.0));
    bool saved = false;
    for (int i = 0; i < 600 && !saved; ++i) {
      auto context = contextWithDeadline();
      v1::Stats stats;
      ASSERT_TRUE(stubs.admin->GetStats(context.get(), v1::StatsRequest(), &stats).ok());
      saved = stats.last_snapshot_age_s() >= 0.0 && stats.map_version() > 0;
      if (!saved) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    ASSERT_TRUE(saved) << server.log();
    std::atomic<bool> running{true};
    std::vector<std::thread> clients;
    clients.emplace_back([&, session] {
      Stubs own(server.target());
      for (int frame = 0; running; ++frame) {
        auto context = contextWithDeadline(5.0);
        v1::BatchAck ack;
        own.ingest->IntegratePoints(context.get(), wallBatch(2.5 + session + 0.01 * frame, 1.5, 0.04, frame), &ack);
        std::this_thread::sleep_for(std::chrono::milliseconds(66));
      }
    });
    for (int q = 0; q < 4; ++q) {
      clients.emplace_back([&] {
        Stubs own(server.target());
        v1::SegmentsRequest request;
        v1::Segment* s = request.add_segments();
        s->mutable_end()->set_x(10.0);
        while (running) {
          auto context = contextWithDeadline(5.0);
          v1::CollisionsReply reply;
          own.query->CheckSegments(context.get(), request, &reply);
        }
      });
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(std::uniform_int_distribution<int>(200, 1500)(rng)));
    server.kill9();
    running = false;
    for (std::thread& t : clients) t.join();
  }
  fs::remove_all(dir.parent_path());
}

// A snapshot that would pass the server's file size limit: RESOURCE_EXHAUSTED naming the file, the
// previous snapshot of that name intact, no temporary file left, and the server still serving.
TEST(ServerSnapshotFaults, FileSizeLimitFailsTheSnapshotAndKeepsThePreviousOne) {
  const fs::path dir = fs::temp_directory_path() / ("cenote-fsize-" + std::to_string(getpid())) / "snapshots";
  fs::remove_all(dir.parent_path());
  fs::create_directories(dir);
  Server server(dir, "fsize", {});
  ASSERT_TRUE(server.listening()) << server.log();
  Stubs stubs(server.target());
  integrate(stubs, wallBatch(2.0, 0.3, 0.05, 1.0));
  auto snapshot = [&](v1::SnapshotReply& reply) {
    v1::SnapshotRequest request;
    request.set_path("dive.vdb");
    auto context = contextWithDeadline();
    return stubs.admin->Snapshot(context.get(), request, &reply);
  };
  v1::SnapshotReply first;
  ASSERT_TRUE(snapshot(first).ok());
  const std::string before = contents(dir / "dive.vdb");
  // `ulimit -f` of the running server: files of at most that snapshot and 512 bytes.
  const rlimit limit{before.size() + 512, RLIM_INFINITY};
  ASSERT_EQ(prlimit(server.pid(), RLIMIT_FSIZE, &limit, nullptr), 0) << std::strerror(errno);
  integrate(stubs, wallBatch(3.0, 3.0, 0.02, 2.0));  // a far bigger map
  v1::SnapshotReply second;
  const grpc::Status status = snapshot(second);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << status.error_message();
  EXPECT_EQ(status.error_message().rfind("cannot write " + (dir / "dive.vdb").string() + ": ", 0), 0u)
      << status.error_message();
  EXPECT_TRUE(contents(dir / "dive.vdb") == before) << "the previous dive.vdb was changed";
  EXPECT_FALSE(hasTemporaries(dir));
  auto context = contextWithDeadline();
  v1::Stats stats;
  EXPECT_TRUE(stubs.admin->GetStats(context.get(), v1::StatsRequest(), &stats).ok()) << server.log();
  const rlimit unlimited{RLIM_INFINITY, RLIM_INFINITY};
  ASSERT_EQ(prlimit(server.pid(), RLIMIT_FSIZE, &unlimited, nullptr), 0) << std::strerror(errno);
  EXPECT_EQ(server.stop(), 0) << server.log();
  fs::remove_all(dir.parent_path());
}

}  // namespace
}  // namespace cenote::server::test
