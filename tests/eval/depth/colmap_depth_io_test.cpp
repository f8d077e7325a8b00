#include "eval/depth/colmap_depth_io.h"

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>

#include "common/error.h"
#include "tests/eval/eval_test_util.h"

namespace cenote::eval {
namespace {

// Writes a file byte by byte in COLMAP's documented layout (read_write_dense.py: header
// "W&H&C&", then float32 in Fortran order over (width, height, channels)), independent of the code
// under test.
void writeByHand(const std::string& path, int w, int h, int c, float (*value)(int x, int y, int ch)) {
  std::ofstream out(path, std::ios::binary);
  out << w << "&" << h << "&" << c << "&";
  for (int ch = 0; ch < c; ++ch) {
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const float v = value(x, y, ch);
        out.write(reinterpret_cast<const char*>(&v), sizeof v);
      }
    }
  }
}

TEST(ColmapDepthIo, ReadsDocumentedLayoutWithXFastest) {
  test::TempDir dir;
  const std::string path = dir / "0001.png.geometric.bin";
  writeByHand(path, 5, 3, 1, [](int x, int y, int) { return 10.0f * y + x; });
  const cv::Mat depth = readColmapArray(path);
  ASSERT_EQ(depth.type(), CV_32FC1);
  ASSERT_EQ(depth.cols, 5);
  ASSERT_EQ(depth.rows, 3);
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 5; ++x) EXPECT_EQ(depth.at<float>(y, x), 10.0f * y + x) << "pixel (" << x << ", " << y << ")";
  }
}

TEST(ColmapDepthIo, ReadsChannelsAsSeparatePlanes) {
  test::TempDir dir;
  const std::string path = dir / "normals.bin";
  writeByHand(path, 2, 2, 3, [](int x, int y, int c) { return 100.0f * c + 10.0f * y + x; });
  const cv::Mat normals = readColmapArray(path);
  ASSERT_EQ(normals.type(), CV_32FC3);
  EXPECT_EQ(normals.at<cv::Vec3f>(1, 0)[2], 210.0f);
  EXPECT_EQ(normals.at<cv::Vec3f>(0, 1)[1], 101.0f);
}

TEST(ColmapDepthIo, WriteThenReadRoundTrips) {
  test::TempDir dir;
  cv::Mat depth(4, 7, CV_32FC1);
  cv::randu(depth, 0.0f, 20.0f);
  writeColmapArray(dir / "a.bin", depth);
  const cv::Mat read = readColmapArray(dir / "a.bin");
  EXPECT_EQ(cv::norm(read, depth, cv::NORM_INF), 0.0);
}

TEST(ColmapDepthIo, TruncatedFileNamesFileAndSizes) {
  test::TempDir dir;
  const std::string path = dir / "short.geometric.bin";
  std::ofstream(path, std::ios::binary) << "4&4&1&" << std::string(12, '\0');
  try {
    readColmapArray(path);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": COLMAP array is truncated (4x4x1"), std::string::npos) << e.what();
  }
}

TEST(ColmapDepthIo, BadHeaderAndMissingFileAreErrors) {
  test::TempDir dir;
  std::ofstream(dir / "text.bin") << "hello world";
  EXPECT_THROW(readColmapArray(dir / "text.bin"), Error);
  std::ofstream(dir / "zero.bin") << "0&4&1&";
  EXPECT_THROW(readColmapArray(dir / "zero.bin"), Error);
  EXPECT_THROW(readColmapArray(dir / "absent.bin"), Error);
  std::ofstream(dir / "long.bin", std::ios::binary) << "1&1&1&" << std::string(8, '\0');
  EXPECT_THROW(readColmapArray(dir / "long.bin"), Error);
}

}  // namespace
}  // namespace cenote::eval
