#include "eval/depth/depth_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>
#include <limits>

#include "common/error.h"
#include "eval/depth/colmap_depth_io.h"
#include "eval/depth/depth_folder.h"
#include "io/image/image_io.h"
#include "tests/eval/eval_test_util.h"

namespace cenote::eval {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

cv::Mat ramp(int w, int h, float base) {
  cv::Mat m(h, w, CV_32FC1);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) m.at<float>(y, x) = base + 0.01f * x + 0.1f * y;
  }
  return m;
}

// Creates the folders `names` in `dir` (the estimate's and the reference's depth maps).
void makeFolders(const test::TempDir& dir, std::initializer_list<const char*> names) {
  for (const char* name : names) std::filesystem::create_directories(dir / name);
}

TEST(DepthMetrics, NoCommonPixelGivesNaNErrorsAndZeroCoverage) {
  cv::Mat est(2, 2, CV_32FC1, cv::Scalar(kNaN));
  cv::Mat ref(2, 2, CV_32FC1, cv::Scalar(1.0f));
  const FrameDepthError f = compareDepthMaps(est, ref, "a");
  EXPECT_EQ(f.common_px, 0);
  EXPECT_EQ(f.reference_px, 4);
  EXPECT_TRUE(std::isnan(f.mean_abs_m));
  EXPECT_TRUE(std::isnan(f.median_abs_m));
  EXPECT_EQ(f.coverage(), 0.0);
}

TEST(DepthMetrics, HandComputedFrame) {
  // Errors on the common pixels: 0.5, 1, 0, 2.5 -> mean 1.0, median (0.5 + 1) / 2 = 0.75.
  cv::Mat est = (cv::Mat_<float>(2, 3) << 1.5f, 3.0f, kNaN, 4.0f, 0.0f, 7.5f);
  cv::Mat ref = (cv::Mat_<float>(2, 3) << 1.0f, 2.0f, 5.0f, 4.0f, 1.0f, 5.0f);
  const FrameDepthError f = compareDepthMaps(est, ref, "frame");
  EXPECT_EQ(f.common_px, 4);
  EXPECT_EQ(f.reference_px, 6);
  EXPECT_EQ(f.estimate_px, 4);  // 0 is no depth
  EXPECT_DOUBLE_EQ(f.mean_abs_m, 1.0);
  EXPECT_DOUBLE_EQ(f.median_abs_m, 0.75);
  EXPECT_DOUBLE_EQ(f.coverage(), 4.0 / 6.0);
}

TEST(DepthMetrics, DatasetMaeIsPooledAndMomIsMedianOfMedians) {
  DepthEvaluation e;
  FrameDepthError a, b, c;
  a.common_px = 1, a.reference_px = 2, a.sum_abs_m = 1.0, a.median_abs_m = 1.0;
  b.common_px = 3, b.reference_px = 3, b.sum_abs_m = 9.0, b.median_abs_m = 2.0;
  c.common_px = 4, c.reference_px = 5, c.sum_abs_m = 2.0, c.median_abs_m = 0.25;
  e.frames = {a, b, c};
  summarizeFrames(e);
  EXPECT_DOUBLE_EQ(e.mae_m, 12.0 / 8.0);
  EXPECT_DOUBLE_EQ(e.mom_m, 1.0);
  EXPECT_DOUBLE_EQ(e.coverage, 8.0 / 10.0);
}

TEST(DepthMetrics, IdenticalFoldersGivePerfectScores) {
  test::TempDir dir;
  makeFolders(dir, {"est", "ref"});
  for (int i = 0; i < 3; ++i) {
    const cv::Mat d = ramp(16, 12, 1.0f + i);
    const std::string name = "10" + std::to_string(i) + ".000000";
    io::writePfm(dir / ("est/" + name + ".depth.pfm"), d);
    io::writePfm(dir / ("ref/" + name + ".depth.pfm"), d);
  }
  const DepthEvaluation e = evaluateDepthFolders(dir / "est", dir / "ref");
  ASSERT_EQ(e.frames.size(), 3u);
  EXPECT_EQ(e.mae_m, 0.0);
  EXPECT_EQ(e.mom_m, 0.0);
  EXPECT_EQ(e.coverage, 1.0);
  EXPECT_EQ(e.common_px, 3 * 16 * 12);
}

TEST(DepthMetrics, MatchesOurPfmWithColmapBinaryAndPngByImageName) {
  test::TempDir dir;
  const std::string est = dir / "est", ref = dir / "ref";
  std::filesystem::create_directories(est);
  std::filesystem::create_directories(ref + "/stereo/depth_maps");
  const cv::Mat truth = ramp(20, 10, 2.0f);
  // Ours: 0.25 m too far everywhere; a confidence map and a preview that must be ignored.
  cv::Mat ours = truth + 0.25f;
  ours.at<float>(3, 2) = kNaN;
  io::writePfm(est + "/0007.depth.pfm", ours);
  io::writePfm(est + "/0007.conf.pfm", cv::Mat(10, 20, CV_32FC1, cv::Scalar(1.0f)));
  io::writeImage(est + "/0007.preview.png", cv::Mat(10, 20, CV_8UC3, cv::Scalar(1, 2, 3)));
  io::writeDepthPng16(est + "/0008.depth.png", truth);
  // COLMAP workspace: geometric beats photometric; a hole (0) in the reference.
  cv::Mat colmap = truth.clone();
  colmap.at<float>(0, 0) = 0.0f;
  writeColmapArray(ref + "/stereo/depth_maps/0007.png.geometric.bin", colmap);
  writeColmapArray(ref + "/stereo/depth_maps/0007.png.photometric.bin", truth * 3.0f);
  writeColmapArray(ref + "/stereo/depth_maps/0008.jpg.geometric.bin", truth);
  writeColmapArray(ref + "/stereo/depth_maps/0009.jpg.geometric.bin", truth);
  const DepthEvaluation e = evaluateDepthFolders(est, ref);
  ASSERT_EQ(e.frames.size(), 2u);
  EXPECT_EQ(e.frames[0].name, "0007");
  EXPECT_EQ(e.frames[0].reference_file.kind, DepthFileKind::kColmapGeometric);
  EXPECT_EQ(e.frames[0].common_px, 198);
  EXPECT_EQ(e.frames[0].reference_px, 199);
  EXPECT_NEAR(e.frames[0].mean_abs_m, 0.25, 1e-5);
  EXPECT_EQ(e.frames[1].name, "0008");
  EXPECT_LT(e.frames[1].mean_abs_m, 0.0006);  // millimetre rounding of the PNG
  ASSERT_EQ(e.only_in_reference.size(), 1u);
  EXPECT_EQ(e.only_in_reference[0], "0009");
  EXPECT_NEAR(e.coverage, 398.0 / 399.0, 1e-12);

  DepthEvaluationOptions photometric;
  photometric.prefer_photometric = true;
  const DepthEvaluation p = evaluateDepthFolders(est, ref, photometric);
  EXPECT_EQ(p.frames[0].reference_file.kind, DepthFileKind::kColmapPhotometric);
  EXPECT_GT(p.frames[0].mean_abs_m, 1.0);
}

TEST(DepthMetrics, ReferenceScaleAndMaxDepthApply) {
  test::TempDir dir;
  makeFolders(dir, {"est", "ref"});
  const cv::Mat d = ramp(8, 8, 1.0f);
  io::writePfm(dir / "est/a.pfm", d);
  io::writePfm(dir / "ref/a.pfm", d * 0.5f);
  DepthEvaluationOptions o;
  o.reference_scale = 2.0;
  EXPECT_NEAR(evaluateDepthFolders(dir / "est", dir / "ref", o).mae_m, 0.0, 1e-6);
  o.max_depth_m = 1.48;  // keeps rows 0..4 (1.0 + 0.1 y + 0.01 x <= 1.48)
  const DepthEvaluation e = evaluateDepthFolders(dir / "est", dir / "ref", o);
  EXPECT_EQ(e.frames[0].reference_px, 8 * 5);
  o.reference_scale = -1.0;
  EXPECT_THROW(evaluateDepthFolders(dir / "est", dir / "ref", o), Error);
}

TEST(DepthMetrics, NumericNamesPairWithinToleranceOnly) {
  test::TempDir dir;
  makeFolders(dir, {"est", "ref"});
  const cv::Mat d = ramp(4, 4, 1.0f);
  // Nanosecond names one writer rounded through a double: 85 ns apart.
  io::writePfm(dir / "est/1700000000066666752.depth.pfm", d);
  io::writePfm(dir / "ref/1700000000066666667.pfm", d);
  io::writePfm(dir / "ref/1700000000133333333.pfm", d);
  EXPECT_THROW(evaluateDepthFolders(dir / "est", dir / "ref"), Error);
  DepthEvaluationOptions o;
  o.name_tolerance = 1000.0;
  const DepthEvaluation e = evaluateDepthFolders(dir / "est", dir / "ref", o);
  ASSERT_EQ(e.frames.size(), 1u);
  EXPECT_EQ(e.frames[0].reference_file.path, dir / "ref/1700000000066666667.pfm");
  ASSERT_EQ(e.only_in_reference.size(), 1u);
  EXPECT_EQ(e.only_in_reference[0], "1700000000133333333");
  o.name_tolerance = 10.0;
  EXPECT_THROW(evaluateDepthFolders(dir / "est", dir / "ref", o), Error);
}

TEST(DepthMetrics, SizeMismatchNamesBothFiles) {
  test::TempDir dir;
  makeFolders(dir, {"est", "ref"});
  io::writePfm(dir / "est/a.pfm", ramp(8, 8, 1.0f));
  io::writePfm(dir / "ref/a.pfm", ramp(8, 7, 1.0f));
  try {
    evaluateDepthFolders(dir / "est", dir / "ref");
    FAIL() << "no error";
  } catch (const Error& e) {
    const std::string text = e.what();
    EXPECT_NE(text.find(dir / "est/a.pfm"), std::string::npos) << text;
    EXPECT_NE(text.find("is 8x8 but reference " + (dir / "ref/a.pfm") + " is 8x7"), std::string::npos) << text;
  }
}

TEST(DepthMetrics, NoCommonNameAndEmptyFolderAreErrors) {
  test::TempDir dir;
  makeFolders(dir, {"est", "ref", "empty"});
  io::writePfm(dir / "est/a.pfm", ramp(4, 4, 1.0f));
  io::writePfm(dir / "ref/b.pfm", ramp(4, 4, 1.0f));
  EXPECT_THROW(evaluateDepthFolders(dir / "est", dir / "ref"), Error);
  EXPECT_THROW(evaluateDepthFolders(dir / "est", dir / "empty"), Error);
  EXPECT_THROW(evaluateDepthFolders(dir / "est", dir / "absent"), Error);
}

TEST(DepthMetrics, ErrorMapMarksUncomparedPixelsNaN) {
  cv::Mat est = (cv::Mat_<float>(1, 3) << 1.0f, kNaN, 3.0f);
  cv::Mat ref = (cv::Mat_<float>(1, 3) << 1.5f, 2.0f, 1.0f);
  cv::Mat error;
  LogHistogram histogram;
  compareDepthMaps(est, ref, "x", &error, &histogram);
  EXPECT_FLOAT_EQ(error.at<float>(0, 0), 0.5f);
  EXPECT_TRUE(std::isnan(error.at<float>(0, 1)));
  EXPECT_FLOAT_EQ(error.at<float>(0, 2), 2.0f);
  EXPECT_EQ(histogram.total(), 2);
}

}  // namespace
}  // namespace cenote::eval
