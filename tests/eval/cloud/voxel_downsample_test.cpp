#include "eval/cloud/voxel_downsample.h"

#include <gtest/gtest.h>

#include <vector>

#include "common/error.h"

namespace cenote::eval {
namespace {

TEST(VoxelDownsample, ZeroKeepsPointsAndVoxelAveragesThem) {
  const std::vector<Eigen::Vector3f> points = {{0.1f, 0.1f, 0.1f}, {0.3f, 0.3f, 0.3f}, {1.5f, 0, 0}, {-0.5f, 0, 0}};
  EXPECT_EQ(voxelDownsample(points, 0.0), points);
  const auto down = voxelDownsample(points, 1.0);
  ASSERT_EQ(down.size(), 3u);
  EXPECT_TRUE(down[0].isApprox(Eigen::Vector3f(-0.5f, 0, 0)));
  EXPECT_TRUE(down[1].isApprox(Eigen::Vector3f(0.2f, 0.2f, 0.2f)));
  EXPECT_TRUE(down[2].isApprox(Eigen::Vector3f(1.5f, 0, 0)));
  EXPECT_THROW(voxelDownsample(points, -1.0), Error);
}

}  // namespace
}  // namespace cenote::eval
