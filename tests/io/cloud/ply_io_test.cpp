#include "io/cloud/ply_io.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "common/atomic_file.h"
#include "common/error.h"

namespace cenote::io {
namespace {

std::string tempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("cenote_ply_test_" + name)).string();
}

TEST(PlyIo, EmptyCloudRoundTrips) {
  const std::string path = tempPath("empty.ply");
  writePly(path, {}, {});
  const PlyPoints read = readPly(path);
  EXPECT_TRUE(read.points.empty());
  EXPECT_TRUE(read.colors.empty());
  std::filesystem::remove(path);
}

TEST(PlyIo, PointsAndColoursRoundTripExactly) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> coord(-100.0f, 100.0f);
  std::uniform_int_distribution<int> byte(0, 255);
  std::vector<Eigen::Vector3f> points(1000);
  std::vector<std::array<uint8_t, 3>> colors(1000);
  for (size_t i = 0; i < points.size(); ++i) {
    points[i] = Eigen::Vector3f(coord(rng), coord(rng), coord(rng));
    colors[i] = {static_cast<uint8_t>(byte(rng)), static_cast<uint8_t>(byte(rng)), static_cast<uint8_t>(byte(rng))};
  }
  const std::string path = tempPath("random.ply");
  writePly(path, points, colors);
  const PlyPoints read = readPly(path);
  ASSERT_EQ(read.points.size(), points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    ASSERT_EQ(read.points[i], points[i]) << "point " << i;
    ASSERT_EQ(read.colors[i], colors[i]) << "colour of point " << i;
  }
  std::filesystem::remove(path);
}

TEST(PlyIo, StreamingWriterCountsEveryBatchAndGreysUncolouredOnes) {
  const std::string path = tempPath("stream.ply");
  {
    PlyWriter writer(path);
    PointBatch coloured;
    coloured.points = {Eigen::Vector3f(1, 2, 3), Eigen::Vector3f(4, 5, 6)};
    coloured.colors = {{{255, 0, 0}}, {{0, 255, 0}}};
    PointBatch plain;
    plain.points = {Eigen::Vector3f(7, 8, 9)};
    writer.append(coloured);
    writer.append(plain);
    EXPECT_FALSE(std::filesystem::exists(path)) << "the file appears only when closed";
    writer.close();
    EXPECT_EQ(writer.count(), 3u);
  }
  const PlyPoints read = readPly(path);
  ASSERT_EQ(read.points.size(), 3u);
  EXPECT_EQ(read.points[2], Eigen::Vector3f(7, 8, 9));
  EXPECT_EQ(read.colors[1], (std::array<uint8_t, 3>{0, 255, 0}));
  EXPECT_EQ(read.colors[2], (std::array<uint8_t, 3>{128, 128, 128}));
  std::filesystem::remove(path);
}

TEST(PlyIo, StreamingWriterKeepsEveryPointPastItsWriteBehindWindow) {
  // Three batches of ~10 MB: the writer hands the first ones to the disk and drops them from the
  // page cache while writing the next; the file must still hold every point, in order.
  const std::string path = tempPath("long.ply");
  constexpr int kBatches = 3, kPerBatch = 700000;
  {
    PlyWriter writer(path);
    for (int b = 0; b < kBatches; ++b) {
      PointBatch batch;
      for (int i = 0; i < kPerBatch; ++i) {
        batch.points.emplace_back(static_cast<float>(b), static_cast<float>(i), 0.5f);
        batch.colors.push_back({static_cast<uint8_t>(b), static_cast<uint8_t>(i % 256), 7});
      }
      writer.append(batch);
    }
    writer.close();
  }
  const PlyPoints read = readPly(path);
  ASSERT_EQ(read.points.size(), static_cast<size_t>(kBatches) * kPerBatch);
  for (size_t j = 0; j < read.points.size(); j += 9973) {
    const int b = static_cast<int>(j / kPerBatch), i = static_cast<int>(j % kPerBatch);
    ASSERT_EQ(read.points[j], Eigen::Vector3f(static_cast<float>(b), static_cast<float>(i), 0.5f)) << "point " << j;
    ASSERT_EQ(read.colors[j][1], static_cast<uint8_t>(i % 256)) << "point " << j;
  }
  EXPECT_EQ(read.points.back(), Eigen::Vector3f(kBatches - 1, kPerBatch - 1, 0.5f));
  std::filesystem::remove(path);
}

TEST(PlyIo, UnclosedWriterLeavesNoFile) {
  const std::string path = tempPath("unclosed.ply");
  { PlyWriter writer(path); }
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_FALSE(std::filesystem::exists(temporaryPathFor(path)));
}

TEST(PlyIo, ReadRejectsOtherFilesWithAClearMessage) {
  const std::string path = tempPath("ascii.ply");
  {
    std::ofstream out(path);
    out << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n";
  }
  try {
    readPly(path);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("format 'ascii' is not supported"), std::string::npos) << e.what();
  }
  {
    std::ofstream out(path, std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\nelement vertex 10\nproperty float x\nproperty float y\n"
           "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
    out << "short";
  }
  EXPECT_THROW(readPly(path), Error);
  EXPECT_THROW(readPly(tempPath("missing.ply")), Error);
  std::filesystem::remove(path);
}

TEST(PlyIo, ReadRefusesAVertexCountTheFileCannotHoldBeforeAllocating) {
  const std::string path = tempPath("claims.ply");
  const auto header = [](const std::string& count) {
    return "ply\nformat binary_little_endian 1.0\nelement vertex " + count +
           "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
           "property uchar blue\nend_header\n";
  };
  std::ofstream(path, std::ios::binary) << header("100000000000000") << std::string(30, '\0');  // two points' worth
  try {
    readPly(path);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kIoFailure);
    EXPECT_EQ(std::string(e.what()), path + ": PLY header's element vertex count 100000000000000 needs 1500000000000000 "
                                            "bytes but the file holds 30 after its header (truncated?)");
  }
  // The same file with the count it holds reads.
  std::ofstream(path, std::ios::binary) << header("2") << std::string(30, '\0');
  EXPECT_EQ(readPly(path).points.size(), 2u);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace cenote::io
