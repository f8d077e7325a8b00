// VIO trajectory files: the OKVIS / SVIn2 CSV by its header's names (any order, unit suffixes, extra
// columns), without a header, its errors; TUM rows in nanoseconds (ORB-SLAM3); format names and detection.
#include "io/trajectory/vio_trajectory.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "common/error.h"
#include "tests/support/error_message.h"

namespace cenote::io {
namespace {

std::string writeFile(const std::string& name, const std::string& text) {
  const std::string path = (std::filesystem::path(::testing::TempDir()) / name).string();
  std::ofstream(path) << text;
  return path;
}

TEST(OkvisCsv, ColumnsByTheirHeaderNames) {
  // The rotation of 90 deg about z: q = (0, 0, sin 45, cos 45); columns reordered, units in the names.
  const std::string path = writeFile("okvis_named.csv",
                                     "q_WS_w [], timestamp [ns], q_WS_x [], q_WS_y [], q_WS_z [], v_WS_W_x, p_WS_W_x [m], "
                                     "p_WS_W_y [m], p_WS_W_z [m]\n"
                                     "0.7071067811865476, 1700000000500000000, 0, 0, 0.7071067811865476, 9, 1, 2, 3\n"
                                     "1, 1700000000600000000, 0, 0, 0, 9, 4, 5, 6\n");
  const Trajectory t = Trajectory::read(path, detectTrajectoryFormat(path));
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t.poses()[0].t_s, 1700000000500000000.0 * 1e-9);
  EXPECT_EQ(t.poses()[0].T_world_cam.translation(), Eigen::Vector3d(1, 2, 3));
  const Eigen::Vector3d x_rotated = t.poses()[0].T_world_cam.linear() * Eigen::Vector3d::UnitX();
  EXPECT_NEAR((x_rotated - Eigen::Vector3d::UnitY()).norm(), 0.0, 1e-12) << "q x y z w: 90 deg about z";
  EXPECT_EQ(t.poses()[1].T_world_cam.translation(), Eigen::Vector3d(4, 5, 6));
}

TEST(OkvisCsv, WithoutHeaderInOkvisOrder) {
  const std::string path = writeFile("okvis_bare.csv", "1000000000, 1, 2, 3, 0, 0, 0, 1, 0, 0, 0\n");
  const Trajectory t = readOkvisCsv(path);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_EQ(t.poses()[0].t_s, 1.0);
  EXPECT_EQ(t.poses()[0].T_world_cam.translation(), Eigen::Vector3d(1, 2, 3));
}

TEST(OkvisCsv, ErrorsNameFileLineAndColumn) {
  const std::string no_column = writeFile("okvis_no_column.csv", "timestamp, p_WS_W_x, p_WS_W_y, p_WS_W_z, q_WS_x\n");
  EXPECT_EQ(cenote::test::errorMessage([&] { readOkvisCsv(no_column); }),
            no_column + ":1: the header has no column q_WS_y (OKVIS / SVIn2: timestamp, p_WS_W_x, "
                        "p_WS_W_y, p_WS_W_z, q_WS_x, q_WS_y, q_WS_z, q_WS_w, ...)");
  const std::string short_row = writeFile("okvis_short.csv", "1000000000, 1, 2, 3, 0, 0, 0\n");
  EXPECT_EQ(cenote::test::errorMessage([&] { readOkvisCsv(short_row); }), short_row + ":1: has 7 values, no q_WS_w");
  const std::string not_unit = writeFile("okvis_norm.csv", "1000000000, 1, 2, 3, 0, 0, 0, 2\n");
  EXPECT_THROW(readOkvisCsv(not_unit), Error);
}

TEST(TumNanoseconds, OrbSlam3RowsInNanosecondsReadAsSeconds) {
  const std::string path = writeFile("orbslam3.txt", "1403636580838555648.000000 1 2 3 0 0 0 1\n"
                                                     "1403636580888555520.000000 4 5 6 0 0 0 1\n");
  EXPECT_EQ(detectTrajectoryFormat(path), TrajectoryFormat::kTum);
  const Trajectory t = Trajectory::read(path, TrajectoryFormat::kTum);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t.poses()[0].t_s, 1403636580838555648.0 * 1e-9);
  EXPECT_NEAR(t.poses()[1].t_s - t.poses()[0].t_s, 0.05, 1e-6);
}

TEST(VioFormats, NamesAndBodyFrames) {
  EXPECT_EQ(parseTrajectoryFormat("okvis"), TrajectoryFormat::kOkvis);
  EXPECT_EQ(parseTrajectoryFormat("svin2"), TrajectoryFormat::kOkvis);
  EXPECT_EQ(parseTrajectoryFormat("openvins"), TrajectoryFormat::kOpenVins);
  EXPECT_STREQ(toString(TrajectoryFormat::kOkvis), "okvis");
  EXPECT_TRUE(describesBody(TrajectoryFormat::kOkvis));
  EXPECT_TRUE(describesBody(TrajectoryFormat::kOpenVins));
  EXPECT_TRUE(describesBody(TrajectoryFormat::kEuroc));
  EXPECT_FALSE(describesBody(TrajectoryFormat::kTum));
  EXPECT_EQ(cenote::test::errorMessage([&] { parseTrajectoryFormat("orb"); }),
            "trajectory format 'orb': must be tum, euroc, kitti, okvis, svin2 or openvins");
}

}  // namespace
}  // namespace cenote::io
