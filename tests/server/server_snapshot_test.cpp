// End-to-end: Admin.Snapshot and Admin.DownloadSnapshot write the format the path's extension
// names (mapping/io/map_file_format.h), and refuse with INVALID_ARGUMENT, naming path and format,
// a format the extension disagrees with, a plain .ply without a format and an unknown extension.
// Raw stubs: the server's own checks, not the C++ client's.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "mapping/io/map_io.h"
#include "io/cloud/pcd_io.h"
#include "io/cloud/ply_io.h"
#include "tests/clients/cpp/server_process.h"
#include "tests/server/server_test_util.h"

namespace cenote::server::test {
namespace {

namespace fs = std::filesystem;
using client::test::ServerProcess;

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

grpc::Status snapshot(Stubs& stubs, const std::string& path, int format) {
  auto context = contextWithDeadline();
  v1::SnapshotRequest request;
  request.set_path(path);
  request.set_format(static_cast<v1::SnapshotFormat>(format));
  v1::SnapshotReply reply;
  return stubs.admin->Snapshot(context.get(), request, &reply);
}

// The whole download: its status, the first chunk's suggested name and the bytes.
struct Download {
  grpc::Status status;
  std::string file_name, data;
};
Download download(Stubs& stubs, const std::string& path, int format) {
  auto context = contextWithDeadline();
  v1::SnapshotRequest request;
  request.set_path(path);
  request.set_format(static_cast<v1::SnapshotFormat>(format));
  auto reader = stubs.admin->DownloadSnapshot(context.get(), request);
  Download d;
  v1::FileChunk chunk;
  while (reader->Read(&chunk)) {
    if (chunk.offset() == 0) d.file_name = chunk.file_name();
    d.data += chunk.data();
  }
  d.status = reader->Finish();
  return d;
}

uint64_t occupiedOnServer(Stubs& stubs) {
  auto context = contextWithDeadline();
  v1::Stats stats;
  EXPECT_TRUE(stubs.admin->GetStats(context.get(), v1::StatsRequest(), &stats).ok());
  return stats.occupied();
}

class ServerSnapshot : public ::testing::Test {
 protected:
  void SetUp() override {
    server_ = std::make_unique<ServerProcess>(CENOTE_SERVER_BINARY);
    stubs_ = std::make_unique<Stubs>(server_->target());
    auto context = contextWithDeadline();
    v1::BatchAck ack;
    ASSERT_TRUE(stubs_->ingest->IntegratePoints(context.get(), wallBatch(2.0, 0.5, 0.05, 1.0), &ack).ok());
    occupied_ = occupiedOnServer(*stubs_);
    ASSERT_GT(occupied_, 100u);
  }
  std::string onServer(const std::string& name) const { return server_->snapshotDirectory() + "/" + name; }

  std::unique_ptr<ServerProcess> server_;
  std::unique_ptr<Stubs> stubs_;
  uint64_t occupied_ = 0;
};

TEST_F(ServerSnapshot, FormatDisagreeingWithTheExtensionIsInvalidArgumentNamingPathAndFormat) {
  grpc::Status status = snapshot(*stubs_, "map.vdb", v1::SNAPSHOT_FORMAT_POINTS_PLY);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message().rfind("path map.vdb, format SNAPSHOT_FORMAT_POINTS_PLY: map.vdb: the extension .vdb "
                                         "means format vdb, not points-ply",
                                         0),
            0u)
      << status.error_message();
  EXPECT_FALSE(fs::exists(onServer("map.vdb")));
  status = snapshot(*stubs_, "mesh.ply", v1::SNAPSHOT_FORMAT_UNSPECIFIED);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("name it .mesh.ply or .points.ply"), std::string::npos) << status.error_message();
  status = snapshot(*stubs_, "map.xyz", v1::SNAPSHOT_FORMAT_UNSPECIFIED);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("map.xyz: the extension .xyz names no map file format"), std::string::npos)
      << status.error_message();
  status = snapshot(*stubs_, "m.points.ply", v1::SNAPSHOT_FORMAT_MESH_PLY);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  status = snapshot(*stubs_, "m.bt", 42);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("path m.bt, format 42: not a snapshot format"), std::string::npos)
      << status.error_message();
  EXPECT_FALSE(fs::exists(onServer("mesh.ply")));
  EXPECT_FALSE(fs::exists(onServer("map.xyz")));
}

TEST_F(ServerSnapshot, EveryExtensionWritesItsFormat) {
  ASSERT_TRUE(snapshot(*stubs_, "m.vdb", v1::SNAPSHOT_FORMAT_UNSPECIFIED).ok());
  EXPECT_EQ(mapping::loadMap(onServer("m.vdb"))->stats().occupied, occupied_);
  ASSERT_TRUE(snapshot(*stubs_, "m.bt", v1::SNAPSHOT_FORMAT_BT).ok());
  EXPECT_EQ(readFile(onServer("m.bt")).rfind("# Octomap OcTree binary file", 0), 0u);
  ASSERT_TRUE(snapshot(*stubs_, "m.ot", v1::SNAPSHOT_FORMAT_UNSPECIFIED).ok());
  EXPECT_EQ(readFile(onServer("m.ot")).rfind("# Octomap OcTree file", 0), 0u);
  ASSERT_TRUE(snapshot(*stubs_, "m.mesh.ply", v1::SNAPSHOT_FORMAT_UNSPECIFIED).ok());
  ASSERT_TRUE(snapshot(*stubs_, "plain.ply", v1::SNAPSHOT_FORMAT_MESH_PLY).ok());
  for (const char* mesh : {"m.mesh.ply", "plain.ply"}) {
    EXPECT_NE(readFile(onServer(mesh)).find("\nelement face "), std::string::npos) << mesh << " is no mesh";
  }
  ASSERT_TRUE(snapshot(*stubs_, "m.points.ply", v1::SNAPSHOT_FORMAT_UNSPECIFIED).ok());
  const io::PlyPoints ply = io::readPly(onServer("m.points.ply"));
  EXPECT_EQ(ply.points.size(), occupied_);
  ASSERT_TRUE(snapshot(*stubs_, "m.pcd", v1::SNAPSHOT_FORMAT_UNSPECIFIED).ok());
  const io::PcdPoints pcd = io::readPcd(onServer("m.pcd"));
  EXPECT_EQ(pcd.points, ply.points);
  EXPECT_EQ(pcd.colors, ply.colors);
}

TEST_F(ServerSnapshot, DownloadsFollowTheClientsFileNameAndOldClientsGetVdb) {
  const Download bt = download(*stubs_, "local.bt", v1::SNAPSHOT_FORMAT_UNSPECIFIED);
  ASSERT_TRUE(bt.status.ok()) << bt.status.error_message();
  EXPECT_EQ(bt.file_name, "map.bt");
  EXPECT_EQ(bt.data.rfind("# Octomap OcTree binary file", 0), 0u);
  const Download pcd = download(*stubs_, "dir/local.pcd", v1::SNAPSHOT_FORMAT_POINTS_PCD);
  ASSERT_TRUE(pcd.status.ok()) << pcd.status.error_message();
  EXPECT_EQ(pcd.file_name, "map.pcd");
  EXPECT_NE(pcd.data.find("\nPOINTS " + std::to_string(occupied_) + "\n"), std::string::npos);
  const Download refused = download(*stubs_, "local.vdb", v1::SNAPSHOT_FORMAT_BT);
  EXPECT_EQ(refused.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(refused.status.error_message().find("path local.vdb, format SNAPSHOT_FORMAT_BT"), std::string::npos)
      << refused.status.error_message();
  const Download old = download(*stubs_, "", v1::SNAPSHOT_FORMAT_UNSPECIFIED);
  ASSERT_TRUE(old.status.ok()) << old.status.error_message();
  EXPECT_EQ(old.file_name, "map.vdb");
  const std::string local = server_->directory() + "/old.vdb";
  std::ofstream(local, std::ios::binary) << old.data;
  EXPECT_EQ(mapping::loadMap(local)->stats().occupied, occupied_);
}

}  // namespace
}  // namespace cenote::server::test
