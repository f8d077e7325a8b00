// server_test_util.h: what the server's end-to-end tests share: a channel to a ServerProcess,
// wire helpers, and the comparison of two maps voxel by voxel.
#pragma once

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <sys/types.h>

#include "cenote/v1/admin.grpc.pb.h"
#include "cenote/v1/ingest.grpc.pb.h"
#include "cenote/v1/query.grpc.pb.h"
#include "mapping/occupancy_map.h"

namespace cenote::server::test {

struct Stubs {
  explicit Stubs(const std::string& target)
      : channel(grpc::CreateChannel(target, grpc::InsecureChannelCredentials())),
        ingest(v1::Ingest::NewStub(channel)),
        query(v1::Query::NewStub(channel)),
        admin(v1::Admin::NewStub(channel)) {}
  std::shared_ptr<grpc::Channel> channel;
  std::unique_ptr<v1::Ingest::Stub> ingest;
  std::unique_ptr<v1::Query::Stub> query;
  std::unique_ptr<v1::Admin::Stub> admin;
};

// A context with a deadline, so that a hung server fails the test instead of hanging it.
inline std::unique_ptr<grpc::ClientContext> contextWithDeadline(double seconds = 60.0) {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(std::chrono::system_clock::now() +
                        std::chrono::milliseconds(static_cast<int64_t>(seconds * 1000.0)));
  return context;
}

// Query.GetMapInfo of the server behind `stubs` (a failed call fails the test and gives an empty info).
inline v1::MapInfo mapInfo(Stubs& stubs) {
  auto context = contextWithDeadline();
  v1::MapInfo info;
  const grpc::Status status = stubs.query->GetMapInfo(context.get(), v1::MapInfoRequest(), &info);
  EXPECT_TRUE(status.ok()) << status.error_message();
  return info;
}

// A fresh folder <temp>/cenote-<suite>-<pid>/<name> for one test's files; the test removes its
// parent (fs::remove_all(dir.parent_path())) when it is done.
std::filesystem::path scratchDir(const std::string& suite, const std::string& name);

// Writes `yaml` to <dir>/config.yaml and returns that path, for the server's --config.
std::string writeConfig(const std::filesystem::path& dir, const std::string& yaml);

// Runs cenote-server with `args` to its exit, its output in <dir>/server.log.
// @return its exit status and everything it printed.
std::pair<int, std::string> runServerToExit(const std::filesystem::path& dir, const std::string& args);

inline void setVec(v1::Vec3* v, double x, double y, double z) {
  v->set_x(x);
  v->set_y(y);
  v->set_z(z);
}

// Voxels known in either map whose state differs, and the number known in either.
struct MapDifference {
  uint64_t known = 0;
  uint64_t different_state = 0;
  uint64_t different_log_odds = 0;
};
MapDifference compareMaps(const mapping::OccupancyMap& a, const mapping::OccupancyMap& b);

// The map on the server, downloaded as .vdb into `dir` and loaded.
std::unique_ptr<mapping::OccupancyMap> downloadMap(v1::Admin::Stub& admin, const std::string& dir);

// A wall of points at x = wall_x_m, |y|, |z| <= half_m, seen from the origin.
v1::PointBatch wallBatch(double wall_x_m, double half_m, double spacing_m, double t_s);

// One thread of a running process, from /proc/<pid>/task/<tid>/{status,stat}.
struct ThreadInfo {
  std::string name;  // e.g. "grpcpp_sync_ser" (gRPC's pollers), "cenote-server" (our own threads)
  std::string cpus;  // Cpus_allowed_list, e.g. "0-1"
  int nice = 0;
};
std::vector<ThreadInfo> threadsOf(pid_t pid);  // "self" for this process: getpid()
// The CPUs this test process may use, as Cpus_allowed_list writes them.
std::string cpusOfThisProcess();

}  // namespace cenote::server::test
