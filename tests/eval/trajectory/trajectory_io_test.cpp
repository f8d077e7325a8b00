#include "eval/trajectory/trajectory_io.h"

#include <gtest/gtest.h>

#include <fstream>

#include "common/error.h"
#include "tests/eval/eval_test_util.h"

namespace cenote::eval {
namespace {

TEST(TrajectoryIo, ReadsColmapImagesTxtAsCameraCentresInTimeOrder) {
  test::TempDir dir;
  // Image 2 (t = 5) rotated 90 degrees about z: q = (cos 45, 0, 0, sin 45); t_cam_world = (1, 0, 0)
  // -> centre = -R^T t = (0, 1, 0). Its points line is empty; image 1 (t = 4) is the identity.
  std::ofstream(dir / "images.txt") << "# Image list with two lines of data per image:\n"
                                       "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
                                       "2 0.70710678118 0 0 0.70710678118 1 0 0 1 5.000000.png\n"
                                       "\n"
                                       "1 1 0 0 0 0 0 -2 1 4.000000.png\n"
                                       "100.5 200.5 -1 300 400 5\n";
  const auto poses = readTrajectoryFile(dir / "images.txt", TrajectoryFileFormat::kAuto);
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_DOUBLE_EQ(poses[0].t_s, 4.0);
  EXPECT_TRUE(poses[0].T_world_cam.translation().isApprox(Eigen::Vector3d(0, 0, 2)));
  EXPECT_DOUBLE_EQ(poses[1].t_s, 5.0);
  EXPECT_TRUE(poses[1].T_world_cam.translation().isApprox(Eigen::Vector3d(0, 1, 0), 1e-9))
      << poses[1].T_world_cam.translation().transpose();
}

TEST(TrajectoryIo, ColmapImageNameMustBeATimestamp) {
  test::TempDir dir;
  std::ofstream(dir / "images.txt") << "1 1 0 0 0 0 0 0 1 frame_a.png\n\n";
  try {
    readColmapImagesTxt(dir / "images.txt");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("images.txt:1: image name 'frame_a.png' is not a timestamp"), std::string::npos)
        << e.what();
  }
}

TEST(TrajectoryIo, DetectsEveryFormat) {
  test::TempDir dir;
  std::ofstream(dir / "t.txt") << "# tum\n1.0 0 0 0 0 0 0 1\n";
  std::ofstream(dir / "k.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n";
  std::ofstream(dir / "e.csv") << "#timestamp [ns],p_x,p_y,p_z,q_w,q_x,q_y,q_z\n1000000000,0,0,0,1,0,0,0\n";
  std::ofstream(dir / "model.txt") << "1 1 0 0 0 0 0 0 1 1.5.png\n\n";
  EXPECT_EQ(detectTrajectoryFileFormat(dir / "t.txt"), TrajectoryFileFormat::kTum);
  EXPECT_EQ(detectTrajectoryFileFormat(dir / "k.txt"), TrajectoryFileFormat::kKitti);
  EXPECT_EQ(detectTrajectoryFileFormat(dir / "e.csv"), TrajectoryFileFormat::kEuroc);
  EXPECT_EQ(detectTrajectoryFileFormat(dir / "model.txt"), TrajectoryFileFormat::kColmap);
  EXPECT_DOUBLE_EQ(readTrajectoryFile(dir / "e.csv", TrajectoryFileFormat::kAuto)[0].t_s, 1.0);
  EXPECT_EQ(readTrajectoryFile(dir / "k.txt", TrajectoryFileFormat::kKitti).size(), 1u);
  EXPECT_THROW(readTrajectoryFile(dir / "absent.txt", TrajectoryFileFormat::kAuto), Error);
  EXPECT_THROW(parseTrajectoryFileFormat("ply"), Error);
  EXPECT_THROW(readTrajectoryFile(dir / "t.txt", TrajectoryFileFormat::kTum, dir / "times.txt"), Error);
}

}  // namespace
}  // namespace cenote::eval
