// depth_index_test: frames.csv as `cenote run --write-depth` writes it reads back to the same
// doubles (names, times, intrinsics, poses); a short row or a word is an error naming file and line.
#include "pipeline/runner/depth_index.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "common/error.h"

namespace cenote::pipeline {
namespace {

namespace fs = std::filesystem;

TEST(DepthIndex, RowsReadBackToTheSameDoubles) {
  const std::string path = (fs::path(::testing::TempDir()) / "frames.csv").string();
  DepthIndexRow a{"1403636580838555648", 1403636580.838555648, Eigen::Matrix3d::Identity(), Eigen::Isometry3d::Identity()};
  a.K << 458.654 / 3.0, 0.0, 367.215, 0.0, 457.296, 248.375 + 1e-13, 0.0, 0.0, 1.0;
  a.T_world_cam = Eigen::Translation3d(0.1 / 3.0, -2.0, 1e-300) *
                  Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, 2.0, 3.0).normalized());
  DepthIndexRow b = a;
  b.name = "000123";
  b.t_s = 12.3;
  {
    DepthIndexWriter writer(path);
    writer.add(a);
    writer.add(b);
  }
  const std::vector<DepthIndexRow> rows = readDepthIndex(path);
  ASSERT_EQ(rows.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const DepthIndexRow& want = i == 0 ? a : b;
    EXPECT_EQ(rows[i].name, want.name);
    EXPECT_EQ(rows[i].t_s, want.t_s);
    EXPECT_EQ(rows[i].K, want.K);
    EXPECT_EQ(rows[i].T_world_cam.matrix(), want.T_world_cam.matrix());
  }
}

TEST(DepthIndex, BadRowsNameTheFileAndLine) {
  const std::string path = (fs::path(::testing::TempDir()) / "bad_frames.csv").string();
  auto error = [&](const std::string& row) {
    std::ofstream(path) << "name,t_s,fx,fy,cx,cy,r00,r01,r02,tx,r10,r11,r12,ty,r20,r21,r22,tz\n" << row << "\n";
    try {
      readDepthIndex(path);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error("f,1,2,3,4"), path + ":2: 5 fields, expected 18 (name,t_s,fx,fy,cx,cy,r00,r01,r02,tx,r10,r11,r12,ty,r20,"
                                       "r21,r22,tz)");
  EXPECT_EQ(error("f,1,two,3"), path + ":2: 'two' is not a number (expected name,t_s,fx,fy,cx,cy,r00,r01,r02,tx,r10,"
                                       "r11,r12,ty,r20,r21,r22,tz)");
  EXPECT_THROW(readDepthIndex(path + ".absent"), NotFoundError);
}

}  // namespace
}  // namespace cenote::pipeline
