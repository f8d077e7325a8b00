#include "pipeline/fusion/back_projection.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <hwy/targets.h>
#include <omp.h>

#include <opencv2/core.hpp>

#include "common/error.h"

namespace cenote::pipeline {
namespace {

TEST(BackProject, EmptyDepthGivesNoPoints) {
  DepthFrame f;
  f.depth = cv::Mat(4, 5, CV_32F, cv::Scalar(std::numeric_limits<float>::infinity()));
  PointBatch batch;
  batch.points.resize(3);
  backProject(f, batch);
  EXPECT_TRUE(batch.empty());
  EXPECT_FALSE(batch.hasColor());
}

TEST(BackProject, PointsAreInTheWorldFrameWithRgbColours) {
  DepthFrame f;
  f.t_s = 4.5;
  f.depth = cv::Mat(3, 4, CV_32F, cv::Scalar(0.0f));
  f.depth.at<float>(1, 2) = 2.0f;
  f.depth.at<float>(2, 0) = 4.0f;
  f.color = cv::Mat(3, 4, CV_8UC3, cv::Scalar(10, 20, 30));  // BGR
  f.color.at<cv::Vec3b>(2, 0) = cv::Vec3b(1, 2, 3);
  f.K << 100.0, 0.0, 2.0, 0.0, 50.0, 1.0, 0.0, 0.0, 1.0;
  f.T_world_cam.translation() = Eigen::Vector3d(10.0, 0.0, 0.0);
  f.T_world_cam.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  PointBatch batch;
  backProject(f, batch);
  ASSERT_EQ(batch.size(), 2u);
  ASSERT_EQ(batch.colors.size(), 2u);
  EXPECT_EQ(batch.t_s, 4.5);
  EXPECT_EQ(batch.origin, Eigen::Vector3d(10.0, 0.0, 0.0));
  // Pixel (2, 1) at 2 m: p_cam = (0, 0, 2) -> world (10, 0, 2).
  EXPECT_NEAR((batch.points[0] - Eigen::Vector3f(10.0f, 0.0f, 2.0f)).norm(), 0.0f, 1e-6f);
  // Pixel (0, 2) at 4 m: p_cam = (4 * -2 / 100, 4 * 1 / 50, 4) = (-0.08, 0.08, 4); rotated 90 deg about z.
  EXPECT_NEAR((batch.points[1] - Eigen::Vector3f(10.0f - 0.08f, -0.08f, 4.0f)).norm(), 0.0f, 1e-6f);
  EXPECT_EQ(batch.colors[0], (std::array<uint8_t, 3>{30, 20, 10}));
  EXPECT_EQ(batch.colors[1], (std::array<uint8_t, 3>{3, 2, 1}));
}

// The runner hands batches back for reuse (frame_pipeline.h): what a batch held before must not
// show, whether it held more points or fewer.
TEST(BackProject, AReusedBatchGetsWhatAFreshOneGets) {
  DepthFrame small, large;
  small.depth = cv::Mat(31, 67, CV_32F);
  large.depth = cv::Mat(97, 67, CV_32F);
  cv::randu(small.depth, -1.0f, 5.0f);
  cv::randu(large.depth, -1.0f, 5.0f);
  for (DepthFrame* f : {&small, &large}) {
    f->color = cv::Mat(f->depth.size(), CV_8UC3);
    cv::randu(f->color, 0, 256);
    f->K << 40.0, 0.0, 33.0, 0.0, 40.0, 48.0, 0.0, 0.0, 1.0;
  }
  for (const auto& [first, second] : {std::pair{&large, &small}, std::pair{&small, &large}}) {
    PointBatch fresh, reused;
    backProject(*first, reused);
    backProject(*second, reused);
    backProject(*second, fresh);
    EXPECT_EQ(reused.points, fresh.points);
    EXPECT_EQ(reused.colors, fresh.colors);
  }
}

TEST(BackProject, OrderAndValuesDoNotDependOnThreads) {
  DepthFrame f;
  f.depth = cv::Mat(97, 53, CV_32F);
  cv::randu(f.depth, -1.0f, 5.0f);  // about a sixth invalid (<= 0)
  f.K << 40.0, 0.0, 26.0, 0.0, 40.0, 48.0, 0.0, 0.0, 1.0;
  PointBatch one, two;
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  backProject(f, one);
  omp_set_num_threads(2);
  backProject(f, two);
  omp_set_num_threads(threads);
  EXPECT_EQ(one.points, two.points);
  EXPECT_GT(one.size(), 97u * 53u / 2);
}

// Every instruction set gives the bits of the plain float expression (one multiply, one add at a
// time), evaluated here in scalar code without fused multiply-adds.
TEST(BackProject, EveryInstructionSetGivesThePlainFloatExpressionsBits) {
  DepthFrame f;
  f.depth = cv::Mat(61, 77, CV_32F);  // 77 columns: a tail narrower than a vector on every target
  cv::randu(f.depth, -1.0f, 5.0f);
  f.depth.at<float>(3, 5) = std::numeric_limits<float>::infinity();
  f.color = cv::Mat(61, 77, CV_8UC3);
  cv::randu(f.color, 0, 256);
  f.K << 40.0, 0.0, 38.3, 0.0, 41.0, 30.1, 0.0, 0.0, 1.0;
  f.T_world_cam.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1.0, 2.0, 3.0).normalized()).toRotationMatrix();
  f.T_world_cam.translation() = Eigen::Vector3d(1.25, -0.5, 3.0);
  const Eigen::Matrix3f RK_inv = (f.T_world_cam.linear() * f.K.inverse()).cast<float>();
  const Eigen::Vector3f t = f.T_world_cam.translation().cast<float>();
  std::vector<Eigen::Vector3f> expected;
  std::vector<std::array<uint8_t, 3>> expected_colours;
  for (int y = 0; y < f.depth.rows; ++y) {
    for (int x = 0; x < f.depth.cols; ++x) {
      const float z = f.depth.at<float>(y, x);
      if (!(z > 0.0f && std::isfinite(z))) continue;
      const Eigen::Vector3f ray = (RK_inv.col(1) * static_cast<float>(y) + RK_inv.col(2)) +
                                  static_cast<float>(x) * RK_inv.col(0);
      expected.push_back(z * ray + t);
      const cv::Vec3b bgr = f.color.at<cv::Vec3b>(y, x);
      expected_colours.push_back({bgr[2], bgr[1], bgr[0]});
    }
  }
  for (const int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    PointBatch batch;
    backProject(f, batch);
    ASSERT_EQ(batch.size(), expected.size()) << hwy::TargetName(target);
    EXPECT_EQ(std::memcmp(batch.points.data(), expected.data(), expected.size() * sizeof(Eigen::Vector3f)), 0)
        << hwy::TargetName(target);
    EXPECT_EQ(batch.colors, expected_colours) << hwy::TargetName(target);
  }
  hwy::SetSupportedTargetsForTest(0);
  EXPECT_GT(expected.size(), 61u * 77u / 2);
}

TEST(BackProject, RejectsColourOfAnotherSize) {
  DepthFrame f;
  f.depth = cv::Mat(3, 4, CV_32F, cv::Scalar(1.0f));
  f.color = cv::Mat(3, 5, CV_8UC3);
  PointBatch batch;
  EXPECT_THROW(backProject(f, batch), Error);
}

}  // namespace
}  // namespace cenote::pipeline
