// Snapshotter: a write that the disk refuses is an I/O failure (INTERNAL through the call guard),
// not the caller's bad argument; stale temporary files of a crashed write are removed at start-up.
#include "server/host/snapshotter.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "common/atomic_file.h"
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
  Snapshotter snapshots(*host, dir.string(), "odom", 0.0);
  EXPECT_TRUE(fs::exists(dir / "map.vdb"));
  EXPECT_TRUE(fs::exists(dir / "notes.tmp-x.txt")) << "not a name temporaryPathFor() gives";
  EXPECT_FALSE(fs::exists(dir / "map.tmp-99999.vdb"));
  EXPECT_FALSE(fs::exists(dir / "sub" / "scene.tmp-7.bt"));
}

}  // namespace
}  // namespace cenote::server
