// Snapshotter: a write that the disk refuses is an I/O failure (INTERNAL through the call guard),
// not the caller's bad argument; stale temporary files of a crashed write are removed at start-up;
// a map.vdb this server did not load is rotated, never overwritten; the quotas remove the oldest
// rotated snapshots first, never the newest. All on real files.
#include "server/host/snapshotter.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>

#include "common/atomic_file.h"
#include "mapping/io/map_io.h"
#include "server/access/call_guard.h"
#include "tests/support/scratch_dir.h"

namespace cenote::server {
namespace {

namespace fs = std::filesystem;

fs::path freshDirectory(const std::string& name) { return test::freshScratchDirectory("snapshotter_test_" + name); }

std::unique_ptr<MapHost> makeHost() {
  return std::make_unique<MapHost>(std::make_unique<mapping::OccupancyMap>(mapping::MapConfig{}), MapHostOptions{});
}

TEST(Snapshotter, WriteWhereTheDiskRefusesIsAnInternalErrorNotAnInvalidArgument) {
  const fs::path dir = freshDirectory("refused");
  const auto host = makeHost();
  Snapshotter snapshots(*host, dir.string(), "odom", 0.0);
  // A file where the snapshot's directory would be: as on a vehicle whose disk went read-only or
  // whose directory was replaced, the write cannot happen (the tests run as root, so permission
  // bits alone would not stop it).
  std::ofstream(dir / "blocked") << "not a directory";
  CallGuard guard;
  grpc::ServerContext context;
  const grpc::Status status = guard.run(&context, "Admin/Snapshot", [&] {
    snapshots.write("blocked/map.vdb", v1::SNAPSHOT_FORMAT_UNSPECIFIED);
    return grpc::Status::OK;
  });
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INTERNAL) << status.error_message();
  const std::string prefix = "cannot write " + (dir / "blocked" / "map.vdb").string() + ": ";
  EXPECT_EQ(status.error_message().rfind(prefix, 0), 0u) << status.error_message();
  EXPECT_EQ(fs::file_size(dir / "blocked"), std::string("not a directory").size());
}

TEST(Snapshotter, StartUpRemovesStaleTemporariesAndKeepsSnapshots) {
  const fs::path dir = freshDirectory("stale");
  fs::create_directories(dir / "sub");
  for (const fs::path& p :
       {dir / "map.vdb", dir / "map.tmp-99999.vdb", dir / "sub" / "scene.tmp-7.bt", dir / "notes.tmp-x.txt"}) {
    std::ofstream(p) << "x";
  }
  const auto host = makeHost();
  Snapshotter snapshots(*host, dir.string(), "odom", 0.0, {.loaded = (dir / "map.vdb").string()});
  EXPECT_TRUE(fs::exists(dir / "map.vdb"));
  EXPECT_TRUE(fs::exists(dir / "notes.tmp-x.txt")) << "not a name temporaryPathFor() gives";
  EXPECT_FALSE(fs::exists(dir / "map.tmp-99999.vdb"));
  EXPECT_FALSE(fs::exists(dir / "sub" / "scene.tmp-7.bt"));
}

std::string contents(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// A map.vdb of a non-empty map, as a previous session left it, written at `written`.
std::string previousSession(const fs::path& dir, fs::file_time_type written) {
  mapping::OccupancyMap map(mapping::MapConfig{});
  PointBatch b;
  b.origin = Eigen::Vector3d::Zero();
  b.points = {Eigen::Vector3f(1.0f, 0.2f, 0.1f), Eigen::Vector3f(1.0f, -0.2f, 0.1f)};
  map.integrate(b);
  mapping::saveMap(map, (dir / "map.vdb").string(), "odom");
  fs::last_write_time(dir / "map.vdb", written);
  return contents(dir / "map.vdb");
}

// 2026-12-02 01:15:00 UTC, plus `s` seconds.
fs::file_time_type at(int s) {
  return std::chrono::file_clock::from_sys(std::chrono::sys_days{std::chrono::year{2026} / 12 / 2} + std::chrono::hours{1} +
                                           std::chrono::minutes{15} + std::chrono::seconds{s});
}

std::vector<std::string> names(const std::vector<fs::path>& paths) {
  std::vector<std::string> out;
  for (const fs::path& p : paths) out.push_back(p.filename().string());
  return out;
}

TEST(Snapshotter, MapVdbNotLoadedIsRotatedNotOverwritten) {
  const fs::path dir = freshDirectory("rotate");
  const std::string before = previousSession(dir, at(0));
  const auto host = makeHost();  // started without --load: an empty map
  Snapshotter snapshots(*host, dir.string(), "odom", 0.0);
  EXPECT_FALSE(fs::exists(dir / "map.vdb"));
  ASSERT_EQ(names(snapshots.rotatedSnapshots()), std::vector<std::string>{"map.20261202T011500Z.vdb"});
  EXPECT_EQ(contents(dir / "map.20261202T011500Z.vdb"), before);
  snapshots.writeLatest();  // the empty map
  ASSERT_TRUE(fs::exists(dir / "map.vdb"));
  EXPECT_NE(contents(dir / "map.vdb"), before);
  EXPECT_EQ(contents(dir / "map.20261202T011500Z.vdb"), before);
  EXPECT_EQ(mapping::loadMap((dir / "map.20261202T011500Z.vdb").string())->stats().occupied, 2u);
  // A restart within the same second of the file's time: another name, nothing lost.
  const std::string second = previousSession(dir, at(0));
  Snapshotter again(*host, dir.string(), "odom", 0.0);
  EXPECT_EQ(names(again.rotatedSnapshots()),
            (std::vector<std::string>{"map.20261202T011500Z.vdb", "map.20261202T011500Z-2.vdb"}));
  EXPECT_EQ(contents(dir / "map.20261202T011500Z-2.vdb"), second);
}

TEST(Snapshotter, MapVdbLoadedIsContinuedAndAnotherLoadedFileStillRotatesIt) {
  const fs::path dir = freshDirectory("loaded");
  const std::string before = previousSession(dir, at(0));
  const auto host = makeHost();
  {
    Snapshotter snapshots(*host, dir.string(), "odom", 0.0, {.loaded = (dir / "." / "map.vdb").string()});
    EXPECT_EQ(contents(dir / "map.vdb"), before);
    EXPECT_TRUE(snapshots.rotatedSnapshots().empty());
  }
  std::ofstream(dir / "other.vdb") << "x";
  Snapshotter snapshots(*host, dir.string(), "odom", 0.0, {.loaded = (dir / "other.vdb").string()});
  EXPECT_FALSE(fs::exists(dir / "map.vdb"));
  EXPECT_EQ(names(snapshots.rotatedSnapshots()), std::vector<std::string>{"map.20261202T011500Z.vdb"});
}

// Rotated snapshots of 1000 bytes written a minute apart, then a map.vdb of 1000 bytes not loaded.
void rotatedFiles(const fs::path& dir, int n) {
  for (int i = 0; i < n; ++i) {
    const fs::path p = dir / ("map.2026120" + std::to_string(i + 1) + "T000000Z.vdb");
    std::ofstream(p) << std::string(1000, 'a' + i);
    fs::last_write_time(p, at(-3600 + 60 * i));
  }
  std::ofstream(dir / "map.vdb") << std::string(1000, 'z');
  fs::last_write_time(dir / "map.vdb", at(0));
}

TEST(Snapshotter, CountQuotaRemovesTheOldestRotatedFirst) {
  const fs::path dir = freshDirectory("count");
  rotatedFiles(dir, 4);
  std::ofstream(dir / "scene.bt") << "an Admin.Snapshot file: not a rotated one";
  const auto host = makeHost();
  Snapshotter snapshots(*host, dir.string(), "odom", 0.0, {.loaded = "", .max_snapshots = 3});
  EXPECT_EQ(names(snapshots.rotatedSnapshots()),
            (std::vector<std::string>{"map.20261203T000000Z.vdb", "map.20261204T000000Z.vdb", "map.20261202T011500Z.vdb"}));
  EXPECT_EQ(contents(dir / "map.20261202T011500Z.vdb"), std::string(1000, 'z'));
  EXPECT_TRUE(fs::exists(dir / "scene.bt"));
}

TEST(Snapshotter, ByteQuotaRemovesTheOldestButNeverTheNewest) {
  {
    const fs::path dir = freshDirectory("bytes");
    rotatedFiles(dir, 4);  // 5000 bytes once map.vdb is rotated
    const auto host = makeHost();
    Snapshotter snapshots(*host, dir.string(), "odom", 0.0,
                          {.loaded = "", .max_snapshots = 10, .max_snapshot_bytes = 2500});
    EXPECT_EQ(names(snapshots.rotatedSnapshots()),
              (std::vector<std::string>{"map.20261204T000000Z.vdb", "map.20261202T011500Z.vdb"}));
    // map.vdb counts too: once written, only the newest rotated one is left beside it.
    snapshots.writeLatest();
    ASSERT_GT(fs::file_size(dir / "map.vdb"), 500u);
    EXPECT_EQ(names(snapshots.rotatedSnapshots()), std::vector<std::string>{"map.20261202T011500Z.vdb"});
  }
  const fs::path dir = freshDirectory("bytes_newest");
  rotatedFiles(dir, 2);
  const auto host = makeHost();
  Snapshotter snapshots(*host, dir.string(), "odom", 0.0,
                        {.loaded = "", .max_snapshots = 10, .max_snapshot_bytes = 10});  // less than any one
  EXPECT_EQ(names(snapshots.rotatedSnapshots()), std::vector<std::string>{"map.20261202T011500Z.vdb"});
}

}  // namespace
}  // namespace cenote::server
