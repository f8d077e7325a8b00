// Ingest.CorrectPoses over gRPC: bad poses are INVALID_ARGUMENT naming the pose, and nothing
// changes; points streamed without a camera pose are never moved (the re-shaping itself:
// tests/mapping/history/, tests/server/host/map_host_corrections_test.cpp).
#include <gtest/gtest.h>

#include "cenote/v1/ingest.grpc.pb.h"
#include "tests/clients/cpp/server_process.h"
#include "tests/server/server_test_util.h"

namespace cenote::server::test {
namespace {

using client::test::ServerProcess;

v1::PoseStamped poseAt(double t_s, double x_m) {
  v1::PoseStamped p;
  p.set_timestamp_s(t_s);
  p.mutable_pose()->mutable_position()->set_x(x_m);
  p.mutable_pose()->mutable_orientation()->set_w(1.0);
  return p;
}

TEST(ServerCorrections, PosesOutOfOrderAreInvalidArgumentAndPointsWithoutPoseStay) {
  // The frame store is off by default: it is what CorrectPoses needs.
  const std::filesystem::path dir = scratchDir("ServerCorrections", "order");
  ServerProcess server(CENOTE_SERVER_BINARY,
                       {.extra_args = {"--config", writeConfig(dir, "server:\n  frame_history: true\n")}});
  Stubs stubs(server.target());
  v1::BatchAck batch_ack;
  {
    auto context = contextWithDeadline();
    ASSERT_TRUE(stubs.ingest->IntegratePoints(context.get(), wallBatch(2.0, 0.5, 0.05, 1.0), &batch_ack).ok());
  }
  v1::PoseCorrection bad;
  *bad.add_poses() = poseAt(1.0, 0.0);
  *bad.add_poses() = poseAt(0.5, 0.0);
  v1::CorrectionAck ack;
  {
    auto context = contextWithDeadline();
    const grpc::Status status = stubs.ingest->CorrectPoses(context.get(), bad, &ack);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_EQ(status.error_message(),
              "correction: pose 1 (t = 0.500000 s) must come after the previous pose (t = 1.000000 s)");
  }
  v1::PoseCorrection good;
  *good.add_poses() = poseAt(0.5, 0.0);
  *good.add_poses() = poseAt(1.5, 0.3);
  {
    auto context = contextWithDeadline();
    ASSERT_TRUE(stubs.ingest->CorrectPoses(context.get(), good, &ack).ok());
  }
  EXPECT_EQ(ack.frames_moved(), 0u);
  EXPECT_EQ(ack.changed_blocks(), 0u);
  EXPECT_EQ(ack.map_version(), batch_ack.map_version());  // nothing moved: the map did not change
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace cenote::server::test
