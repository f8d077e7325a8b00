#include "io/trajectory/trajectory.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "common/error.h"

namespace cenote::io {
namespace {

std::string write(const std::string& name, const std::string& text) {
  const std::string path = testing::TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

TEST(Trajectory, InterpolatesTranslationLinearlyAndRotationBySlerp) {
  // Two samples 1 s apart: from the origin, facing along x, to (2, 4, 0) after 90 degrees about z.
  const std::string path = write("two.tum", "10.0 0 0 0 0 0 0 1\n11.0 2 4 0 0 0 0.7071067811865476 0.7071067811865476\n");
  const Trajectory t = Trajectory::read(path, TrajectoryFormat::kTum);
  const auto pose = t.poseAt(10.25, 2.0);
  ASSERT_TRUE(pose);
  EXPECT_NEAR(pose->translation().x(), 0.5, 1e-12);
  EXPECT_NEAR(pose->translation().y(), 1.0, 1e-12);
  // A quarter of the way: 22.5 degrees about z.
  const Eigen::AngleAxisd aa(pose->linear());
  EXPECT_NEAR(aa.angle(), M_PI / 8.0, 1e-9);
  EXPECT_NEAR(aa.axis().z(), 1.0, 1e-9);
}

TEST(Trajectory, NeverGuessesOutsideTheSamplesOrAcrossLongGaps) {
  const std::string path = write("gap.tum", "1.0 0 0 0 0 0 0 1\n1.1 1 0 0 0 0 0 1\n3.0 2 0 0 0 0 0 1\n");
  const Trajectory t = Trajectory::read(path, TrajectoryFormat::kTum);
  EXPECT_FALSE(t.poseAt(0.99, 0.5)) << "before the first sample";
  EXPECT_FALSE(t.poseAt(3.01, 0.5)) << "after the last sample";
  EXPECT_FALSE(t.poseAt(2.0, 0.5)) << "in a 1.9 s gap";
  EXPECT_TRUE(t.poseAt(2.0, 2.0)) << "the same gap, allowed";
  ASSERT_TRUE(t.poseAt(3.0, 0.5)) << "exactly at the last sample";
  EXPECT_DOUBLE_EQ(t.poseAt(3.0, 0.5)->translation().x(), 2.0);
}

TEST(Trajectory, ReadsEurocCsvInNanosecondsWithWFirstQuaternions) {
  const std::string path = write(
      "gt.csv", "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []\n"
                "1403636579758555392,4.688319,-1.786938,0.783338,0.534108,-0.153029,-0.827383,-0.082152\n"
                "1403636579763555584,4.688177,-1.786770,0.787350,0.534640,-0.152990,-0.826976,-0.082863\n");
  const Trajectory t = Trajectory::read(path, TrajectoryFormat::kEuroc);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_NEAR(t.poses()[0].t_s, 1403636579.758555392, 1e-6);
  const Eigen::Quaterniond q(t.poses()[0].T_world_cam.linear());
  EXPECT_NEAR(std::abs(q.w()), 0.534108, 1e-5);
  EXPECT_EQ(detectTrajectoryFormat(path), TrajectoryFormat::kEuroc);
}

TEST(Trajectory, ReadsKittiRowsWithTimesFile) {
  const std::string poses = write("00.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n"
                                            "1 0 0 0.1 0 1 0 -0.02 0 0 1 0.8\n");
  const std::string times = write("times.txt", "0.000000e+00\n1.036594e-01\n");
  const Trajectory t = Trajectory::read(poses, TrajectoryFormat::kKitti, times);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_NEAR(t.poses()[1].t_s, 0.1036594, 1e-9);
  EXPECT_NEAR(t.poses()[1].T_world_cam.translation().z(), 0.8, 1e-12);
  EXPECT_EQ(detectTrajectoryFormat(poses), TrajectoryFormat::kKitti);
  const Trajectory no_times = Trajectory::read(poses, TrajectoryFormat::kKitti);
  EXPECT_DOUBLE_EQ(no_times.poses()[1].t_s, 0.1);
}

TEST(Trajectory, BodyPosesBecomeCameraPosesThroughTheExtrinsics) {
  const std::string path = write("body.tum", "0 1 2 3 0 0 0.7071067811865476 0.7071067811865476\n");
  Eigen::Isometry3d T_body_cam = Eigen::Isometry3d::Identity();
  T_body_cam.translation() = Eigen::Vector3d(0.1, 0.0, 0.0);
  const Trajectory cam = Trajectory::read(path, TrajectoryFormat::kTum).transformedBy(T_body_cam);
  // The body is turned 90 degrees about z: its x axis points along world y.
  EXPECT_NEAR(cam.poses()[0].T_world_cam.translation().x(), 1.0, 1e-12);
  EXPECT_NEAR(cam.poses()[0].T_world_cam.translation().y(), 2.1, 1e-12);
}

TEST(Trajectory, MalformedFilesAreErrorsNamingFileAndLine) {
  try {
    Trajectory::read(write("bad.csv", "#header\n1,2,3\n"), TrajectoryFormat::kEuroc);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.csv:2:"), std::string::npos) << e.what();
  }
  try {
    Trajectory::read(write("nan.tum", "0 nan 0 0 0 0 0 1\n"), TrajectoryFormat::kTum);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("nan.tum:1:"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Trajectory::read(write("order.tum", "2 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n"), TrajectoryFormat::kTum), Error);
  EXPECT_THROW(Trajectory::read(testing::TempDir() + "/absent.tum", TrajectoryFormat::kTum), Error);
  EXPECT_THROW(detectTrajectoryFormat(write("five.txt", "1 2 3 4 5\n")), Error);
  EXPECT_THROW(parseTrajectoryFormat("colmap"), Error);
}

// 10 Hz poses stamped like a real recording (nanoseconds since 1970, read into seconds): gaps of
// exactly 0.1 s, which doubles near 1.4e9 s represent only to within 2.4e-7 s.
std::string writeEpochPoses(const std::string& name, int count, int64_t period_ns) {
  std::string text;
  for (int i = 0; i < count; ++i) {
    const int64_t t_ns = 1403636579000000000LL + i * period_ns;
    text += std::to_string(t_ns) + "," + std::to_string(0.1 * i) + ",0,0,1,0,0,0\n";
  }
  return write(name, text);
}

TEST(Trajectory, GapsOfExactlyMaxGapAreBridgedAtEpochTimestamps) {
  const Trajectory t = Trajectory::read(writeEpochPoses("epoch10hz.csv", 50, 100000000), TrajectoryFormat::kEuroc);
  // Frames 1 ms after each pose (a camera clock a little behind the VIO's): every one between two
  // samples exactly max_gap_s = 0.1 s apart.
  int posed = 0;
  for (int i = 0; i < 49; ++i) {
    const double t_s = (1403636579000000000LL + i * 100000000LL + 1000000LL) * 1e-9;
    const auto pose = t.poseAt(t_s, 0.1);
    if (!pose) {
      ADD_FAILURE() << "frame " << i << " (t = " << t_s << " s): no pose between samples 0.1 s apart";
      continue;
    }
    ++posed;
    EXPECT_NEAR(pose->translation().x(), 0.1 * i + 0.001, 1e-5) << "frame " << i;
  }
  EXPECT_EQ(posed, 49);
  // A gap a little over max_gap_s (0.1 s + 10 us) is still refused: the slack is 1 us.
  const Trajectory wide = Trajectory::read(writeEpochPoses("epoch_wide.csv", 3, 100010000), TrajectoryFormat::kEuroc);
  EXPECT_FALSE(wide.poseAt(1403636579.05, 0.1));
}

}  // namespace
}  // namespace cenote::io
