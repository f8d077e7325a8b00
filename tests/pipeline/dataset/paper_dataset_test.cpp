// The paper's layout: filename_mapping.csv in seconds with a header row, rows without both images
// counted; intrinsics.yaml written by OpenCV's FileStorage with T in millimetres, in metres or absent.
#include "pipeline/dataset/paper_dataset.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "common/error.h"

namespace cenote::pipeline {
namespace {

namespace fs = std::filesystem;

// A dataset folder of three rows, the third without its right image; T written as given (or not at all).
fs::path makeDataset(const std::string& name, const cv::Mat& T) {
  const fs::path root = fs::path(::testing::TempDir()) / name;
  fs::remove_all(root);
  fs::create_directories(root / "left");
  fs::create_directories(root / "right");
  const cv::Mat image(4, 6, CV_8UC1, cv::Scalar(7));
  for (const char* file : {"1612345678.250000.png", "1612345678.350000.png", "1612345678.450000.png"}) {
    cv::imwrite((root / "left" / file).string(), image);
    if (std::string(file) != "1612345678.450000.png") cv::imwrite((root / "right" / file).string(), image);
  }
  std::ofstream(root / "filename_mapping.csv") << "ts,filename\n1612345678.250000,1612345678.250000.png\n"
                                                  "1612345678.350000,1612345678.350000.png\n"
                                                  "1612345678.450000,1612345678.450000.png\n";
  cv::FileStorage fs((root / "intrinsics.yaml").string(), cv::FileStorage::WRITE);
  fs << "image_width" << 6 << "image_height" << 4;
  fs << "K1" << cv::Mat(cv::Matx33d(500, 0, 3, 0, 500, 2, 0, 0, 1)) << "D1" << cv::Mat(cv::Matx14d(-0.1, 0.01, 0, 0));
  fs << "K2" << cv::Mat(cv::Matx33d(501, 0, 3, 0, 501, 2, 0, 0, 1)) << "D2" << cv::Mat(cv::Matx14d(-0.1, 0.01, 0, 0));
  fs << "baseline" << 120.0;
  if (!T.empty()) fs << "R" << cv::Mat(cv::Matx33d::eye()) << "T" << T;
  fs.release();
  return root;
}

TEST(PaperDataset, SecondsHeaderRowAndRowsWithoutBothImages) {
  const fs::path root = makeDataset("paper_mm", cv::Mat(cv::Vec3d(-120, 0, 0)));
  ASSERT_TRUE(PaperDataset::looksLike(root.string()));
  const PaperDataset d(root.string());
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d.unpairedFrames(), 1u);
  EXPECT_EQ(d.timestamp(0), 1612345678.25);
  EXPECT_EQ(d.timestamp(1), 1612345678.35);
  EXPECT_EQ(d.frameName(1), "1612345678.350000");
  EXPECT_EQ(d.load(0).left.size(), cv::Size(6, 4));
  EXPECT_EQ(d.calibration().T, cv::Vec3d(-0.12, 0, 0)) << "millimetres";
  EXPECT_EQ(d.calibration().right.K(0, 0), 501.0);
  EXPECT_EQ(d.calibration().left.distortion, (std::vector<double>{-0.1, 0.01, 0, 0}));
  EXPECT_FALSE(d.referenceCloud());
  EXPECT_FALSE(d.defaultTrajectory()) << "no poses.txt";
  EXPECT_EQ(d.describe(), "paper layout " + root.string() + ": 2 stereo frames, 1 rows without both images left out");
}

TEST(PaperDataset, TInMetresOrAbsent) {
  EXPECT_EQ(PaperDataset(makeDataset("paper_m", cv::Mat(cv::Vec3d(-0.12, 0, 0))).string()).calibration().T,
            cv::Vec3d(-0.12, 0, 0));
  const PaperDataset absent(makeDataset("paper_none", cv::Mat()).string());
  EXPECT_EQ(absent.calibration().T, cv::Vec3d(-0.12, 0, 0));
  EXPECT_EQ(absent.calibration().R, cv::Matx33d::eye());
}

TEST(PaperDataset, TMatchingTheBaselineInNeitherUnitIsAnError) {
  const fs::path root = makeDataset("paper_bad", cv::Mat(cv::Vec3d(-60, 0, 0)));
  try {
    PaperDataset d(root.string());
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), (root / "intrinsics.yaml").string() +
                                         ": T has length 60.000000, which matches baseline = 120.000000 mm neither in "
                                         "millimetres nor in metres");
  }
  fs::remove(root / "intrinsics.yaml");
  EXPECT_FALSE(PaperDataset::looksLike(root.string()));
}

}  // namespace
}  // namespace cenote::pipeline
