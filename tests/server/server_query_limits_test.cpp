// End-to-end: work bounded per request on a real server. A batch beyond server.limits.max_query_voxels
// is refused before it runs; a long batch ends at its deadline or when cancelled instead of holding
// the map; an integration sent during a long batch completes before the batch does; an extract of
// exactly its derived voxel limit fits the message limit, and one voxel more is refused up front.
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <thread>

#include "tests/clients/cpp/server_process.h"
#include "tests/server/server_test_util.h"

namespace cenote::server::test {
namespace {

namespace fs = std::filesystem;
using client::test::ServerProcess;

constexpr double kVoxel = 0.05;  // config/default.yaml

// A configuration file holding `yaml`, in the test's temporary directory.
std::string configFile(const std::string& name, const std::string& yaml) {
  const fs::path path = fs::temp_directory_path() / ("cenote-query-limits-" + std::to_string(getpid()) + "-" + name);
  std::ofstream(path) << yaml;
  return path.string();
}

v1::SegmentsRequest segments(int n, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  v1::SegmentsRequest request;
  for (int i = 0; i < n; ++i) {
    v1::Segment* s = request.add_segments();
    setVec(s->mutable_start(), a.x(), a.y(), a.z());
    setVec(s->mutable_end(), b.x(), b.y(), b.z());
  }
  return request;
}

// The server refused the call as beyond a limit, saying `message`.
void expectResourceExhausted(const grpc::Status& status, const std::string& message) {
  EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(status.error_message(), message);
}

// The calls and errors the server has recorded for `method` (Admin.GetStats).
v1::MethodStats methodStats(Stubs& stubs, const std::string& method) {
  auto context = contextWithDeadline();
  v1::Stats stats;
  EXPECT_TRUE(stubs.admin->GetStats(context.get(), v1::StatsRequest(), &stats).ok());
  for (const v1::MethodStats& m : stats.methods())
    if (m.method() == method) return m;
  return v1::MethodStats();
}

// Polls until the server has finished one call of `method` (a hung handler never does: the poll
// gives up after `polls` tries, failing the test instead of hanging it).
bool serverFinishedCall(Stubs& stubs, const std::string& method, int polls = 600) {
  for (int i = 0; i < polls; ++i) {
    if (methodStats(stubs, method).calls() >= 1) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return false;
}

TEST(ServerQueryLimits, BatchBeyondTheVoxelBudgetIsResourceExhaustedNamingTheKey) {
  const std::string config = configFile("budget.yaml", "server:\n  limits:\n    max_query_voxels: 1000000\n");
  ServerProcess server(CENOTE_SERVER_BINARY, {.extra_args = {"--config", config}});
  Stubs stubs(server.target());
  // Voxels 0 .. 999 along x: 1000 voxels a segment.
  const Eigen::Vector3d a(0.5 * kVoxel, 0.5 * kVoxel, 0.5 * kVoxel), b(999.5 * kVoxel, 0.5 * kVoxel, 0.5 * kVoxel);
  {
    auto context = contextWithDeadline();
    v1::CollisionsReply reply;
    const grpc::Status status = stubs.query->CheckSegments(context.get(), segments(1000, a, b), &reply);
    ASSERT_TRUE(status.ok()) << "exactly the budget: " << status.error_message();
    EXPECT_EQ(reply.results_size(), 1000);
  }
  {
    auto context = contextWithDeadline();
    v1::CollisionsReply reply;
    expectResourceExhausted(stubs.query->CheckSegments(context.get(), segments(1001, a, b), &reply),
                            "map query: 1001 segments may visit up to 1001000 voxels, more than the budget "
                            "server.limits.max_query_voxels = 1000000");
  }
  {
    v1::BoxesRequest request;  // 100^3 voxels each
    for (int i = 0; i < 2; ++i) {
      setVec(request.add_boxes()->mutable_min(), 0, 0, 0);
      setVec(request.mutable_boxes(i)->mutable_max(), 100 * kVoxel, 100 * kVoxel, 100 * kVoxel);
    }
    auto context = contextWithDeadline();
    v1::BoxesReply reply;
    expectResourceExhausted(stubs.query->GetBoxes(context.get(), request, &reply),
                            "map query: 2 boxes may visit up to 2000000 voxels, more than the budget "
                            "server.limits.max_query_voxels = 1000000");
  }
  {
    v1::RaycastRequest request;  // to the edge of the map's range: 2^20 - 8 voxels
    setVec(request.add_rays()->mutable_origin(), a.x(), a.y(), a.z());
    setVec(request.mutable_rays(0)->mutable_direction(), 1, 0, 0);
    request.set_max_range_m(1e9);
    auto context = contextWithDeadline();
    v1::CollisionsReply reply;
    expectResourceExhausted(stubs.query->Raycast(context.get(), request, &reply),
                            "map query: 1 rays may visit up to 1048568 voxels, more than the budget "
                            "server.limits.max_query_voxels = 1000000");
  }
  {
    v1::ExtractRequest request;  // 200 x 100 x 100 voxels
    setVec(request.mutable_box()->mutable_min(), 0, 0, 0);
    setVec(request.mutable_box()->mutable_max(), 200 * kVoxel, 100 * kVoxel, 100 * kVoxel);
    auto context = contextWithDeadline();
    v1::ExtractReply reply;
    expectResourceExhausted(stubs.query->ExtractVoxels(context.get(), request, &reply),
                            "box voxels: 2000000 items, more than the limit server.limits.max_query_voxels = 1000000");
  }
  fs::remove(config);
}

// 100k segments of 2 M voxels each across an empty map: hours of walking, within a budget of 1e12.
constexpr int kLongBatch = 100000;
const Eigen::Vector3d kFarWest(-50000.0, 5.025, 0.025), kFarEast(50000.0, 5.025, 0.025);

TEST(ServerQueryLimits, LongBatchEndsAtItsDeadlineOrWhenCancelled) {
  const std::string config = configFile("long.yaml", "server:\n  limits:\n    max_query_voxels: 1000000000000\n");
  ServerProcess server(CENOTE_SERVER_BINARY, {.extra_args = {"--config", config}});
  Stubs stubs(server.target());
  const v1::SegmentsRequest request = segments(kLongBatch, kFarWest, kFarEast);
  {
    auto context = contextWithDeadline(1.0);
    v1::CollisionsReply reply;
    const grpc::Status status = stubs.query->CheckSegments(context.get(), request, &reply);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED) << status.error_message();
    // The server gave up too (it answers the call when its handler ends; without the deadline
    // check inside the batch it would walk for hours).
    ASSERT_TRUE(serverFinishedCall(stubs, "Query/CheckSegments")) << server.log();
    EXPECT_EQ(methodStats(stubs, "Query/CheckSegments").errors(), 1u);
  }
  {
    grpc::ClientContext context;
    v1::RaycastRequest rays;  // the same walks as rays
    for (int i = 0; i < kLongBatch; ++i) {
      setVec(rays.add_rays()->mutable_origin(), kFarWest.x(), kFarWest.y(), kFarWest.z());
      setVec(rays.mutable_rays(i)->mutable_direction(), 1, 0, 0);
    }
    rays.set_max_range_m(100000.0);
    std::thread cancel([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
      context.TryCancel();
    });
    v1::CollisionsReply reply;
    const grpc::Status status = stubs.query->Raycast(&context, rays, &reply);
    cancel.join();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::CANCELLED) << status.error_message();
    ASSERT_TRUE(serverFinishedCall(stubs, "Query/Raycast")) << server.log();
    EXPECT_EQ(methodStats(stubs, "Query/Raycast").errors(), 1u);
  }
  fs::remove(config);
}

// Events in the order they happened, from any thread.
struct EventLog {
  std::atomic<int> next{0};
  int stamp() { return next++; }
};

// A long batch of 20k segments from (0, 100, 0) through the voxel P = (200, 100, 0): while P is
// unknown each walks 1 M voxels (minutes for the batch); an integration makes P occupied, after which each stops there. The integration, sent
// while the batch runs, completes before it; the batch's items before it found no hit, those after
// it the hit at P, and none went back (each item saw one state of the map).
TEST(ServerQueryLimits, IntegrationDuringALongBatchCompletesBeforeTheBatch) {
  const std::string config = configFile("interleave.yaml", "server:\n  limits:\n    max_query_voxels: 1000000000000\n");
  ServerProcess server(CENOTE_SERVER_BINARY, {.extra_args = {"--config", config}});
  Stubs stubs(server.target());
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(64 << 20);  // the reply: about 1 MB
  const auto query = v1::Query::NewStub(
      grpc::CreateCustomChannel(server.target(), grpc::InsecureChannelCredentials(), args));
  constexpr int kItems = 20000;
  const v1::SegmentsRequest request = segments(kItems, Eigen::Vector3d(0.025, 5.025, 0.025),
                                               Eigen::Vector3d(50000.0, 5.025, 0.025));
  v1::PointBatch wall;
  setVec(wall.mutable_origin(), 10.025, 5.025, 2.025);
  for (const double c : {10.025, 5.025, 0.025}) wall.add_xyz(c);
  bool conclusive = false;
  for (int attempt = 0; attempt < 3 && !conclusive; ++attempt) {
    {  // P unknown again
      auto context = contextWithDeadline();
      v1::ChangeReply reset;
      ASSERT_TRUE(stubs.admin->Reset(context.get(), v1::ResetRequest(), &reset).ok());
    }
    EventLog log;
    int batch_done = -1, integration_done = -1;
    v1::CollisionsReply reply;
    grpc::Status batch_status;
    std::thread batch([&] {
      auto context = contextWithDeadline(600.0);
      batch_status = query->CheckSegments(context.get(), request, &reply);
      batch_done = log.stamp();
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(500 << attempt));  // the batch is under way
    auto context = contextWithDeadline(120.0);
    v1::BatchAck ack;
    const grpc::Status status = stubs.ingest->IntegratePoints(context.get(), wall, &ack);
    integration_done = log.stamp();
    batch.join();
    ASSERT_TRUE(status.ok()) << status.error_message();
    ASSERT_TRUE(batch_status.ok()) << batch_status.error_message();
    ASSERT_EQ(reply.results_size(), kItems);
    EXPECT_LT(integration_done, batch_done);
    int first_hit = kItems;
    for (int i = 0; i < kItems; ++i) {
      const v1::Collision& r = reply.results(i);
      if (r.hit() && first_hit == kItems) first_hit = i;
      ASSERT_EQ(r.hit(), i >= first_hit) << "segment " << i << " went back to the map before the integration";
      if (r.hit()) {
        ASSERT_EQ(r.hit_voxel().x(), 200) << "segment " << i;
        ASSERT_EQ(r.hit_voxel().y(), 100) << "segment " << i;
        ASSERT_EQ(r.hit_voxel().z(), 0) << "segment " << i;
      }
    }
    EXPECT_LT(first_hit, kItems) << "no segment saw the integration";
    // Attempt again, waiting longer, when the integration came before the batch began.
    conclusive = first_hit > 0;
  }
  EXPECT_TRUE(conclusive) << "the integration was applied before the batch began, three times";
  fs::remove(config);
}

// max_message_bytes = 1 MiB: an extract may hold (1048576 - 64) / 17 = 61677 voxels. A box of
// exactly that many, every voxel known and coloured at indices of 3-byte varints (the worst case),
// arrives through a channel limited to 1 MiB; a box of one voxel more is refused before it is read.
TEST(ServerQueryLimits, ExtractOfExactlyTheLimitFitsTheMessageLimit) {
  constexpr int kMessageBytes = 1 << 20;
  constexpr int kLimit = (kMessageBytes - 64) / 17;
  ASSERT_EQ(kLimit, 61677);
  const std::string config = configFile(
      "extract.yaml", "server:\n  limits:\n    max_message_bytes: " + std::to_string(kMessageBytes) + "\n");
  ServerProcess server(CENOTE_SERVER_BINARY, {.extra_args = {"--config", config}});
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(kMessageBytes);
  args.SetMaxSendMessageSize(kMessageBytes);
  auto channel = grpc::CreateCustomChannel(server.target(), grpc::InsecureChannelCredentials(), args);
  auto query = v1::Query::NewStub(channel);
  auto ingest = v1::Ingest::NewStub(channel);
  // 89 x 63 x 11 = 61677 voxels from index (9000, 9000, 9000): zigzag(9000) = 18000 >= 2^14.
  const Eigen::Vector3i lo(9000, 9000, 9000), size(89, 63, 11);
  ASSERT_EQ(size.prod(), kLimit);
  for (int x = 0; x < size.x(); ++x) {  // one batch per x plane, seen from beside the box
    v1::PointBatch batch;
    setVec(batch.mutable_origin(), (lo.x() + x + 0.5) * kVoxel, (lo.y() - 20) * kVoxel, (lo.z() - 20) * kVoxel);
    std::string rgb;
    for (int y = 0; y < size.y(); ++y) {
      for (int z = 0; z < size.z(); ++z) {
        for (const int i : {lo.x() + x, lo.y() + y, lo.z() + z}) batch.add_xyz_f32(static_cast<float>((i + 0.5) * kVoxel));
        rgb += {static_cast<char>(x), static_cast<char>(y), static_cast<char>(z)};
      }
    }
    batch.set_rgb(rgb);
    auto context = contextWithDeadline();
    v1::BatchAck ack;
    const grpc::Status status = ingest->IntegratePoints(context.get(), batch, &ack);
    ASSERT_TRUE(status.ok()) << status.error_message();
  }
  v1::ExtractRequest request;
  request.set_include_unknown(true);
  setVec(request.mutable_box()->mutable_min(), lo.x() * kVoxel, lo.y() * kVoxel, lo.z() * kVoxel);
  setVec(request.mutable_box()->mutable_max(), (lo.x() + size.x()) * kVoxel, (lo.y() + size.y()) * kVoxel,
         (lo.z() + size.z()) * kVoxel);
  {
    auto context = contextWithDeadline();
    v1::ExtractReply reply;
    const grpc::Status status = query->ExtractVoxels(context.get(), request, &reply);
    ASSERT_TRUE(status.ok()) << status.error_message();
    ASSERT_EQ(reply.states_size(), kLimit);
    int occupied = 0;
    for (int i = 0; i < reply.states_size(); ++i) occupied += reply.states(i) == v1::VOXEL_STATE_OCCUPIED;
    EXPECT_EQ(occupied, kLimit);  // every voxel known: the worst case
    EXPECT_EQ(reply.rgb().size(), 3u * kLimit);
    EXPECT_LE(reply.ByteSizeLong(), static_cast<size_t>(kMessageBytes));
    EXPECT_GT(reply.ByteSizeLong(), static_cast<size_t>(kMessageBytes - 100));  // within the 64 bytes besides
  }
  {
    // A line of kLimit + 1 voxels along z.
    setVec(request.mutable_box()->mutable_min(), lo.x() * kVoxel, lo.y() * kVoxel, lo.z() * kVoxel);
    setVec(request.mutable_box()->mutable_max(), (lo.x() + 1) * kVoxel, (lo.y() + 1) * kVoxel,
           (lo.z() + kLimit + 1) * kVoxel);
    auto context = contextWithDeadline();
    v1::ExtractReply reply;
    const grpc::Status status = query->ExtractVoxels(context.get(), request, &reply);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_EQ(status.error_message(),
              "box: 61678 voxels, more than an extract may hold: 61677 (server.limits.max_box_voxels = 10000000, and "
              "(server.limits.max_message_bytes = 1048576 - 64) / 17 bytes per voxel at the worst)");
  }
  fs::remove(config);
}

}  // namespace
}  // namespace cenote::server::test
