#include "eval/cloud/cloud_io.h"

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>

#include "common/error.h"
#include "io/cloud/ply_io.h"
#include "tests/eval/eval_test_util.h"
#include "tests/support/error_message.h"

namespace cenote::eval {
namespace {

template <typename T>
void put(std::ofstream& out, T v, bool big_endian = false) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &v, sizeof(T));
  if (big_endian) std::reverse(bytes, bytes + sizeof(T));
  out.write(bytes, sizeof(T));
}

std::string errorOf(const std::string& path) {
  return cenote::test::errorMessage([&] { readCloud(path); });
}

TEST(CloudIo, ReadsCenotesOwnPly) {
  test::TempDir dir;
  io::writePly(dir / "a.ply", {{1, 2, 3}, {4, 5, 6}}, {});
  const Cloud c = readCloud(dir / "a.ply");
  ASSERT_EQ(c.points.size(), 2u);
  EXPECT_EQ(c.points[1], Eigen::Vector3f(4, 5, 6));
}

TEST(CloudIo, ReadsAsciiPlyWithFacesAndExtraProperties) {
  test::TempDir dir;
  std::ofstream(dir / "a.ply") << "ply\nformat ascii 1.0\ncomment hi\nelement vertex 3\nproperty float nx\n"
                                  "property double x\nproperty double y\nproperty double z\nproperty uchar red\n"
                                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                                  "0 1 2 3 255\n0 4 5 6 0\n0 -1.5 0 1e2 7\n3 0 1 2\n";
  const Cloud c = readCloud(dir / "a.ply");
  ASSERT_EQ(c.points.size(), 3u);
  EXPECT_EQ(c.points[2], Eigen::Vector3f(-1.5f, 0.0f, 100.0f));
}

TEST(CloudIo, ReadsBigEndianDoublePlyAfterAnotherElement) {
  test::TempDir dir;
  {
    std::ofstream out(dir / "b.ply", std::ios::binary);
    out << "ply\nformat binary_big_endian 1.0\nelement camera 1\nproperty list uchar float k\n"
           "element vertex 2\nproperty double x\nproperty double y\nproperty double z\nproperty int id\nend_header\n";
    put<uint8_t>(out, 2);
    put<float>(out, 1.0f, true);
    put<float>(out, 2.0f, true);
    for (int i = 0; i < 2; ++i) {
      put<double>(out, 1.0 + i, true);
      put<double>(out, -2.0, true);
      put<double>(out, 0.5, true);
      put<int32_t>(out, i, true);
    }
  }
  const Cloud c = readCloud(dir / "b.ply");
  ASSERT_EQ(c.points.size(), 2u);
  EXPECT_EQ(c.points[1], Eigen::Vector3f(2.0f, -2.0f, 0.5f));
}

TEST(CloudIo, ReadsAsciiAndBinaryPcdAndDropsNaN) {
  test::TempDir dir;
  std::ofstream(dir / "a.pcd") << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\n"
                                  "COUNT 1 1 1 1\nWIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n"
                                  "1 2 3 0\nnan nan nan 0\n4 5 6 1\n";
  const Cloud a = readCloud(dir / "a.pcd");
  ASSERT_EQ(a.points.size(), 2u);
  EXPECT_EQ(a.non_finite_dropped, 1u);
  EXPECT_EQ(a.points[1], Eigen::Vector3f(4, 5, 6));
  {
    std::ofstream out(dir / "b.pcd", std::ios::binary);
    out << "VERSION 0.7\nFIELDS intensity x y z\nSIZE 2 8 8 8\nTYPE U F F F\nCOUNT 1 1 1 1\nWIDTH 2\nHEIGHT 1\n"
           "POINTS 2\nDATA binary\n";
    for (int i = 0; i < 2; ++i) {
      put<uint16_t>(out, 7);
      put<double>(out, i);
      put<double>(out, 2.0 * i);
      put<double>(out, -1.0);
    }
  }
  const Cloud b = readCloud(dir / "b.pcd");
  ASSERT_EQ(b.points.size(), 2u);
  EXPECT_EQ(b.points[1], Eigen::Vector3f(1, 2, -1));
  writePcdAscii(dir / "c.pcd", b.points);
  EXPECT_EQ(readCloud(dir / "c.pcd").points, b.points);
}

TEST(CloudIo, MalformedFilesNameTheFileAndTheProblem) {
  test::TempDir dir;
  EXPECT_NE(errorOf(dir / "absent.ply").find("absent.ply: no such file"), std::string::npos);
  std::ofstream(dir / "noxyz.ply") << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float a\nend_header\n1\n";
  EXPECT_NE(errorOf(dir / "noxyz.ply").find("noxyz.ply: PLY vertex element has no x, y and z"), std::string::npos);
  std::ofstream(dir / "short.ply") << "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                                      "property float z\nend_header\n1 2 3\n4 5\n";
  EXPECT_NE(errorOf(dir / "short.ply").find("short.ply: PLY vertex 1 of 2: file ends early"), std::string::npos)
      << errorOf(dir / "short.ply");
  std::ofstream(dir / "word.ply") << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                     "property float z\nend_header\n1 two 3\n";
  EXPECT_NE(errorOf(dir / "word.ply").find("'two' is not a number"), std::string::npos);
  std::ofstream(dir / "trunc.ply", std::ios::binary) << "ply\nformat binary_little_endian 1.0\nelement vertex 5\n"
                                                        "property float x\nproperty float y\nproperty float z\n"
                                                        "end_header\n"
                                                     << std::string(20, '\0');
  EXPECT_NE(errorOf(dir / "trunc.ply").find("trunc.ply: PLY file is truncated in element 'vertex' (1 of 5"),
            std::string::npos)
      << errorOf(dir / "trunc.ply");
  std::ofstream(dir / "z.pcd") << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nPOINTS 1\n"
                                  "DATA binary_compressed\n";
  // PCD goes through PCL's reader (io/cloud/pcd_io.h): binary_compressed is read, a body
  // shorter than announced is refused naming the file.
  EXPECT_EQ(errorOf(dir / "z.pcd"), "cannot read " + (dir / "z.pcd") +
                                        " as PCD: pcl::PCDReader failed (-1; its message "
                                        "is printed above): a malformed header, a truncated body or not a PCD file");
  std::ofstream(dir / "few.pcd") << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 3\nHEIGHT 1\nPOINTS 3\n"
                                    "DATA ascii\n1 2 3\n";
  EXPECT_EQ(errorOf(dir / "few.pcd").rfind("cannot read " + (dir / "few.pcd") + " as PCD: pcl::PCDReader failed", 0), 0u)
      << errorOf(dir / "few.pcd");
  std::ofstream(dir / "x.txt") << "hello\n";
  EXPECT_NE(errorOf(dir / "x.txt").find("neither a PLY nor a PCD"), std::string::npos);
}

TEST(CloudIo, PlyCountsBeyondTheFileAreRefusedBeforeAllocating) {
  test::TempDir dir;
  // 10^14 vertices announced, 2 held: refused, not reserved (2.4 PB).
  std::ofstream(dir / "claims.ply", std::ios::binary) << "ply\nformat binary_little_endian 1.0\n"
                                                         "element vertex 100000000000000\nproperty float x\n"
                                                         "property float y\nproperty float z\nend_header\n"
                                                      << std::string(24, '\0');
  EXPECT_EQ(errorOf(dir / "claims.ply"),
            dir / "claims.ply" + ": PLY file is truncated in element 'vertex' (2 of 100000000000000 read)");
  std::ofstream(dir / "claims_ascii.ply") << "ply\nformat ascii 1.0\nelement vertex 100000000000000\n"
                                             "property float x\nproperty float y\nproperty float z\nend_header\n"
                                             "1 2 3\n";
  EXPECT_EQ(errorOf(dir / "claims_ascii.ply"),
            dir / "claims_ascii.ply" + ": PLY vertex 1 of 100000000000000: file ends early (truncated)");
  // A list whose length overflows size_t when multiplied by its item size.
  std::ofstream(dir / "list.ply", std::ios::binary) << "ply\nformat binary_little_endian 1.0\nelement face 1\n"
                                                       "property list uint int vertex_indices\nelement vertex 1\n"
                                                       "property float x\nproperty float y\nproperty float z\n"
                                                       "end_header\n\xff\xff\xff\xff"
                                                    << std::string(12, '\0');
  EXPECT_EQ(errorOf(dir / "list.ply"), dir / "list.ply" + ": PLY file is truncated in element 'face' (0 of 1 read)");
}

}  // namespace
}  // namespace cenote::eval
