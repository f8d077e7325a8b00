#include "io/image/image_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>

#include "common/error.h"

namespace cenote::io {
namespace {

std::string temp(const std::string& name) { return testing::TempDir() + "/" + name; }

TEST(Pfm, RoundTripKeepsValuesInfinityAndRowOrder) {
  cv::Mat map(3, 4, CV_32FC1);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) map.at<float>(y, x) = 10.0f * y + x + 0.25f;
  map.at<float>(1, 2) = std::numeric_limits<float>::infinity();
  writePfm(temp("a.pfm"), map);
  const cv::Mat back = readPfm(temp("a.pfm"));
  ASSERT_EQ(back.size(), map.size());
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) {
      const float a = map.at<float>(y, x), b = back.at<float>(y, x);
      EXPECT_TRUE(a == b || (std::isinf(a) && std::isinf(b))) << "(" << x << ", " << y << ")";
    }
}

TEST(Pfm, FirstRowInTheFileIsTheBottomImageRow) {
  cv::Mat map = (cv::Mat_<float>(2, 1) << 1.0f, 2.0f);
  writePfm(temp("order.pfm"), map);
  std::ifstream in(temp("order.pfm"), std::ios::binary);
  std::string magic;
  int w, h;
  double scale;
  in >> magic >> w >> h >> scale;
  in.get();
  float first;
  in.read(reinterpret_cast<char*>(&first), 4);
  EXPECT_EQ(magic, "Pf");
  EXPECT_LT(scale, 0.0);  // little-endian
  EXPECT_EQ(first, 2.0f);
}

TEST(Pfm, MissingTruncatedAndForeignFilesAreErrors) {
  EXPECT_THROW(readPfm(temp("none.pfm")), Error);
  std::ofstream(temp("short.pfm"), std::ios::binary) << "Pf\n4 4\n-1\n1234";
  EXPECT_THROW(readPfm(temp("short.pfm")), Error);
  std::ofstream(temp("png.pfm"), std::ios::binary) << "\x89PNG\r\n";
  EXPECT_THROW(readPfm(temp("png.pfm")), Error);
}

TEST(ReadImage, NamesTheFileWhenMissingOrNotAnImage) {
  try {
    readImage(temp("missing.png"), cv::IMREAD_COLOR);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.png: no such file"), std::string::npos);
  }
  std::ofstream(temp("text.png")) << "not an image";
  try {
    readImage(temp("text.png"), cv::IMREAD_COLOR);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("not a readable image"), std::string::npos);
  }
}

TEST(ColorizeMap, NonFiniteIsBlackAndRangeEndsGetTheColourMapEnds) {
  cv::Mat map = (cv::Mat_<float>(1, 3) << 0.0f, std::numeric_limits<float>::infinity(), 10.0f);
  const cv::Mat colour = colorizeMap(map, 0.0, 10.0);
  EXPECT_EQ(colour.at<cv::Vec3b>(0, 1), cv::Vec3b(0, 0, 0));
  EXPECT_NE(colour.at<cv::Vec3b>(0, 0), colour.at<cv::Vec3b>(0, 2));
}

}  // namespace
}  // namespace cenote::io
