// pose_buffer_test: the server's buffer of streamed poses stays bounded by count and by time, and
// one mis-stamped pose (far in the future) never locks out the stream's real poses.
#include "server/services/pose_buffer.h"

#include <gtest/gtest.h>

#include <chrono>

#include "server/wire/status_error.h"

namespace cenote::server {
namespace {

io::StampedPose poseAtX(double t_s, double x) {
  io::StampedPose p;
  p.t_s = t_s;
  p.T_world_cam = Eigen::Isometry3d::Identity();
  p.T_world_cam.translation() = Eigen::Vector3d(x, 0.0, 0.0);
  return p;
}

std::chrono::steady_clock::time_point now() { return std::chrono::steady_clock::now(); }

// The error code and message of add(), or OK and "" when it was accepted.
std::pair<grpc::StatusCode, std::string> addResult(PoseBuffer& buffer, const io::StampedPose& pose) {
  try {
    buffer.add(pose);
    return {grpc::StatusCode::OK, ""};
  } catch (const StatusError& e) {
    return {e.code(), e.what()};
  }
}

TEST(PoseBuffer, InterpolatesBetweenTheTwoPosesAroundAFrame) {
  PoseBuffer buffer(PoseBufferLimits{});
  buffer.add(poseAtX(10.0, 0.0));
  buffer.add(poseAtX(10.1, 1.0));
  const std::optional<Eigen::Isometry3d> T = buffer.poseAt(10.025, 0.2, now());
  ASSERT_TRUE(T.has_value());
  EXPECT_NEAR(T->translation().x(), 0.25, 1e-12);
}

TEST(PoseBuffer, HoldsAtMostMaxPosesWhateverTheirSpacing) {
  PoseBuffer buffer(PoseBufferLimits{.history_s = 60.0, .max_poses = 1000, .max_jump_s = 60.0});
  // A million poses a nanosecond apart: all within history_s, so only the count bounds them.
  for (int i = 0; i < 1'000'000; ++i) buffer.add(poseAtX(100.0 + i * 1e-9, 0.0));
  EXPECT_EQ(buffer.received(), 1'000'000u);
  EXPECT_EQ(buffer.size(), 1000u);
}

TEST(PoseBuffer, DropsPosesOlderThanTheHistory) {
  PoseBuffer buffer(PoseBufferLimits{.history_s = 1.0, .max_poses = 100000, .max_jump_s = 60.0});
  for (int i = 0; i <= 100; ++i) buffer.add(poseAtX(i * 0.1, 0.0));  // 10 s at 10 Hz
  EXPECT_LE(buffer.size(), 12u);
  EXPECT_GE(buffer.size(), 10u);
  EXPECT_FALSE(buffer.poseAt(2.05, 0.2, now()).has_value());  // dropped
  EXPECT_TRUE(buffer.poseAt(9.55, 0.2, now()).has_value());
}

TEST(PoseBuffer, RefusesAPoseFarAfterTheNewestAndKeepsTakingRealOnes) {
  PoseBuffer buffer(PoseBufferLimits{});
  buffer.add(poseAtX(1000.0, 0.0));
  const auto [code, message] = addResult(buffer, poseAtX(1e18, 5.0));
  EXPECT_EQ(code, grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(message.find("server.pose_max_jump_s"), std::string::npos) << message;
  // The stream goes on: the next real pose is taken, and frames between them find their pose.
  EXPECT_EQ(addResult(buffer, poseAtX(1000.1, 1.0)).first, grpc::StatusCode::OK);
  const std::optional<Eigen::Isometry3d> T = buffer.poseAt(1000.05, 0.2, now());
  ASSERT_TRUE(T.has_value());
  EXPECT_NEAR(T->translation().x(), 0.5, 1e-12);
}

TEST(PoseBuffer, AFarFuturePoseTakenBeforeAnyFrameIsDroppedByTheFirstFrame) {
  PoseBuffer buffer(PoseBufferLimits{});
  // Nothing to compare with yet: the first pose is taken, whatever its time.
  ASSERT_EQ(addResult(buffer, poseAtX(1e18, 5.0)).first, grpc::StatusCode::OK);
  // Real poses are not after it: refused while it is there.
  EXPECT_EQ(addResult(buffer, poseAtX(1000.0, 0.0)).first, grpc::StatusCode::INVALID_ARGUMENT);
  // A frame at the cameras' time shows it does not belong to this clock: it goes.
  buffer.noteFrameTime(1000.0);
  EXPECT_EQ(buffer.size(), 0u);
  EXPECT_EQ(addResult(buffer, poseAtX(1000.0, 0.0)).first, grpc::StatusCode::OK);
  EXPECT_EQ(addResult(buffer, poseAtX(1000.1, 1.0)).first, grpc::StatusCode::OK);
  EXPECT_TRUE(buffer.poseAt(1000.05, 0.2, now()).has_value());
  // And a pose far after the frames' clock is refused even with the buffer empty of later poses.
  EXPECT_EQ(addResult(buffer, poseAtX(5000.0, 0.0)).first, grpc::StatusCode::INVALID_ARGUMENT);
}

}  // namespace
}  // namespace cenote::server
