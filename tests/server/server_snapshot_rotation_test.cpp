// End-to-end: a server started without --load in a snapshot directory that holds the previous
// session's map.vdb keeps that file (renamed, said so at start-up) and writes its own map.vdb; one
// started with --load of it continues it.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <thread>

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

TEST(ServerSnapshotRotation, RestartWithoutLoadKeepsThePreviousMapVdb) {
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
    EXPECT_EQ(contents(kept[0]), first);
    EXPECT_NE(server.log().find("map.vdb was not loaded (no --load): kept as " + kept[0].filename().string()),
              std::string::npos)
        << server.log();
    Stubs stubs(server.target());
    auto context = contextWithDeadline();
    v1::BatchAck ack;  // something to write at SIGTERM
    ASSERT_TRUE(stubs.ingest->IntegratePoints(context.get(), wallBatch(3.0, 0.5, 0.05, 1.0), &ack).ok());
    ASSERT_EQ(server.stop(), 0) << server.log();
    EXPECT_EQ(contents(kept[0]), first);
    EXPECT_NE(contents(dir / "map.vdb"), first);
  }
  const std::string second = contents(dir / "map.vdb");
  {  // with --load of it: continued, nothing more rotated
    Server server(dir, "third", {"--load", (dir / "map.vdb").string()});
    ASSERT_TRUE(server.listening()) << server.log();
    EXPECT_EQ(rotated(dir).size(), 1u) << server.log();
    EXPECT_EQ(contents(dir / "map.vdb"), second);
    ASSERT_EQ(server.stop(), 0) << server.log();
  }
  fs::remove_all(dir.parent_path());
}

}  // namespace
}  // namespace cenote::server::test
