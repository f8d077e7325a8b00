#include "io/trajectory/tum_trajectory.h"

#include <gtest/gtest.h>

#include <sstream>

#include "common/error.h"
#include "tests/support/error_message.h"

namespace cenote::io {
namespace {

TumTrajectory parse(const std::string& text) {
  std::istringstream in(text);
  return TumTrajectory::parse(in, "traj.txt");
}

std::string errorOf(const std::string& text) {
  return cenote::test::errorMessage([&] { parse(text); });
}

TEST(TumTrajectory, EmptyFileGivesNoPoses) {
  const TumTrajectory t = parse("# only a comment\n\n");
  EXPECT_TRUE(t.empty());
  EXPECT_FALSE(t.lookup(0.0, 1.0).has_value());
}

TEST(TumTrajectory, ReadsPosesAsCameraToWorld) {
  // 90 degrees about z: qz = qw = sqrt(1/2).
  const TumTrajectory t = parse("# t tx ty tz qx qy qz qw\n1.0 1 2 3 0 0 0.70710678 0.70710678\n");
  ASSERT_EQ(t.size(), 1u);
  const Eigen::Vector3d p_world = t.poses()[0].T_world_cam * Eigen::Vector3d(1.0, 0.0, 0.0);
  EXPECT_NEAR((p_world - Eigen::Vector3d(1.0, 3.0, 3.0)).norm(), 0.0, 1e-7);
}

TEST(TumTrajectory, LookupTakesTheNearestPoseWithinTolerance) {
  const TumTrajectory t = parse("1.0 0 0 0 0 0 0 1\n2.0 1 0 0 0 0 0 1\n3.0 2 0 0 0 0 0 1\n");
  EXPECT_EQ(t.lookup(2.0004, 0.001)->t_s, 2.0);
  EXPECT_EQ(t.lookup(1.9996, 0.001)->t_s, 2.0);
  EXPECT_EQ(t.lookup(0.9995, 0.001)->t_s, 1.0);
  EXPECT_EQ(t.lookup(3.0009, 0.001)->t_s, 3.0);
  EXPECT_FALSE(t.lookup(2.5, 0.001).has_value());
  EXPECT_FALSE(t.lookup(3.1, 0.001).has_value());
  EXPECT_EQ(t.lookup(2.5, 1.0)->t_s, 2.0) << "a tie goes to the earlier pose";
}

TEST(TumTrajectory, ErrorsNameFileLineAndProblem) {
  EXPECT_EQ(errorOf("1.0 0 0 0 0 0 0 1\n2.0 0 0\n"), "traj.txt:2: expected 8 numbers 't tx ty tz qx qy qz qw', found 3");
  EXPECT_EQ(errorOf("1.0 0 0 0 0 0 0 1 9\n"), "traj.txt:1: expected 8 numbers 't tx ty tz qx qy qz qw', found more");
  EXPECT_EQ(errorOf("1.0 0 zero 0 0 0 0 1\n"), "traj.txt:1: 'zero' is not a number");
  EXPECT_NE(errorOf("# header\n1.0 0 nan 0 0 0 0 1\n").find("traj.txt:2: non-finite value"), std::string::npos);
  EXPECT_NE(errorOf("1.0 0 0 0 0 0 0 0.9\n").find("traj.txt:1: quaternion (qx qy qz qw) has norm 0.9"), std::string::npos);
  EXPECT_NE(errorOf("2.0 0 0 0 0 0 0 1\n1.0 0 0 0 0 0 0 1\n").find("traj.txt:2: timestamp 1 is not after"),
            std::string::npos);
  EXPECT_THROW(TumTrajectory::read("/nonexistent/traj.txt"), Error);
}

// The reference paper's poses.txt may begin with a row of column names; only the first row may be one.
TEST(TumTrajectory, SkipsOneHeaderRowOfColumnNames) {
  const TumTrajectory t = parse("# comment\nstamp tx ty tz qx qy qz qw\n1.0 0 0 0 0 0 0 1\n2.0 1 0 0 0 0 0 1\n");
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t.poses()[0].t_s, 1.0);
  EXPECT_EQ(errorOf("stamp tx ty tz qx qy qz qw\nframe 1\n"), "traj.txt:2: 'frame' is not a number");
  EXPECT_EQ(errorOf("1.0 0 0 0 0 0 0 1\nstamp tx ty tz qx qy qz qw\n"), "traj.txt:2: 'stamp' is not a number");
  EXPECT_NE(errorOf("NaN 0 0 0 0 0 0 1\n").find("traj.txt:1: non-finite value"), std::string::npos);
}

TEST(TumTrajectory, AcceptsWindowsLineEndingsAndTabs) {
  const TumTrajectory t = parse("# comment\r\n1.0\t0 0 0 0 0 0 1\r\n2.0 0 0 0 0 0 0 1\r\n");
  EXPECT_EQ(t.size(), 2u);
}

TEST(TumTrajectory, NearlyUnitQuaternionIsNormalised) {
  const TumTrajectory t = parse("1.0 0 0 0 0 0 0 1.0004\n");
  const Eigen::Matrix3d R = t.poses()[0].T_world_cam.linear();
  EXPECT_NEAR((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);
}

}  // namespace
}  // namespace cenote::io
