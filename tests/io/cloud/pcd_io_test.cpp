// pcd_io_test.cpp: PCD through PCL (pcd_io.h) against files from independent writers: hand-written
// ASCII text from the PCD v0.7 specification, the bytes of PCL's binary output decoded here by the
// specification's layout, and eval's own hand-written ASCII writer; then round trips.
#include "io/cloud/pcd_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>

#include "common/error.h"
#include "tests/support/error_message.h"

namespace cenote::io {
namespace {

std::string tempPath(const std::string& name) { return testing::TempDir() + "/cenote_pcd_test_" + name; }

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::string errorOf(const std::string& path) {
  return cenote::test::errorMessage([&] { readPcd(path); });
}

// The header lines of a PCD file up to and including DATA, and the offset of the body.
std::vector<std::string> headerOf(const std::string& bytes, size_t& body) {
  std::vector<std::string> lines;
  size_t pos = 0;
  while (pos < bytes.size()) {
    const size_t end = bytes.find('\n', pos);
    lines.push_back(bytes.substr(pos, end - pos));
    pos = end + 1;
    if (lines.back().rfind("DATA", 0) == 0) break;
  }
  body = pos;
  return lines;
}

TEST(PcdIo, ReadsTheSpecificationsAsciiExampleLayout) {
  // PCD v0.7 as the specification writes it: an organised 2 x 2 cloud, rgb packed as U 4
  // (0x00RRGGBB), a NaN point (PCL's "missing"), an extra field and a comment.
  const std::string path = tempPath("spec.pcd");
  std::ofstream(path) << "# .PCD v0.7 - Point Cloud Data file format\n"
                         "VERSION 0.7\n"
                         "FIELDS x y z rgb intensity\n"
                         "SIZE 4 4 4 4 2\n"
                         "TYPE F F F U U\n"
                         "COUNT 1 1 1 1 1\n"
                         "WIDTH 2\n"
                         "HEIGHT 2\n"
                         "VIEWPOINT 0 0 0 1 0 0 0\n"
                         "POINTS 4\n"
                         "DATA ascii\n"
                         "0.93773 0.33763 0 16711680 7\n"
                         "0.90805 0.35641 -1.5 65280 7\n"
                         "nan nan nan 0 7\n"
                         "-2.25 1e-3 4096 255 7\n";
  const PcdPoints c = readPcd(path);
  ASSERT_EQ(c.points.size(), 3u);
  EXPECT_EQ(c.non_finite_dropped, 1u);
  EXPECT_EQ(c.points[0], Eigen::Vector3f(0.93773f, 0.33763f, 0.0f));
  EXPECT_EQ(c.points[1], Eigen::Vector3f(0.90805f, 0.35641f, -1.5f));
  EXPECT_EQ(c.points[2], Eigen::Vector3f(-2.25f, 1e-3f, 4096.0f));
  ASSERT_EQ(c.colors.size(), 3u);
  EXPECT_EQ(c.colors[0], (std::array<uint8_t, 3>{255, 0, 0}));
  EXPECT_EQ(c.colors[1], (std::array<uint8_t, 3>{0, 255, 0}));
  EXPECT_EQ(c.colors[2], (std::array<uint8_t, 3>{0, 0, 255}));
}

TEST(PcdIo, ReadsDoubleCoordinatesWithoutColour) {
  const std::string path = tempPath("double.pcd");
  {
    std::ofstream out(path, std::ios::binary);
    out << "VERSION 0.7\nFIELDS x y z\nSIZE 8 8 8\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA binary\n";
    const double v[6] = {0.1, -2.0, 1e6, 3.5, 0.0, -7.25};
    out.write(reinterpret_cast<const char*>(v), sizeof(v));
  }
  const PcdPoints c = readPcd(path);
  ASSERT_EQ(c.points.size(), 2u);
  EXPECT_TRUE(c.colors.empty());
  EXPECT_EQ(c.points[0], Eigen::Vector3f(0.1f, -2.0f, 1e6f));
  EXPECT_EQ(c.points[1], Eigen::Vector3f(3.5f, 0.0f, -7.25f));
}

TEST(PcdIo, BinaryWrittenThroughPclHasTheSpecificationsLayout) {
  const std::vector<Eigen::Vector3f> points = {{1.0f, -2.0f, 0.5f}, {0.125f, 3.0e3f, -1e-4f}, {0, 0, 0}};
  const std::vector<std::array<uint8_t, 3>> colors = {{255, 0, 0}, {1, 2, 3}, {0, 128, 255}};
  const std::string path = tempPath("layout.pcd");
  writePcd(path, points, colors, PcdEncoding::kBinary);
  const std::string bytes = readFile(path);
  size_t body = 0;
  const std::vector<std::string> header = headerOf(bytes, body);
  auto line = [&](const std::string& key) {
    for (const std::string& l : header) {
      if (l.rfind(key + " ", 0) == 0) return l;
    }
    return std::string("(no " + key + ")");
  };
  EXPECT_EQ(line("VERSION"), "VERSION 0.7");
  EXPECT_EQ(line("FIELDS"), "FIELDS x y z rgb");
  EXPECT_EQ(line("SIZE"), "SIZE 4 4 4 4");
  EXPECT_EQ(line("COUNT"), "COUNT 1 1 1 1");
  EXPECT_EQ(line("WIDTH"), "WIDTH 3");
  EXPECT_EQ(line("HEIGHT"), "HEIGHT 1");
  EXPECT_EQ(line("POINTS"), "POINTS 3");
  EXPECT_EQ(line("DATA"), "DATA binary");
  ASSERT_EQ(bytes.size() - body, 3u * 16) << "x y z rgb, 4 bytes each";
  for (size_t i = 0; i < points.size(); ++i) {
    float xyz[3];
    uint32_t rgb;
    std::memcpy(xyz, bytes.data() + body + 16 * i, 12);
    std::memcpy(&rgb, bytes.data() + body + 16 * i + 12, 4);
    EXPECT_EQ(Eigen::Vector3f(xyz[0], xyz[1], xyz[2]), points[i]) << "point " << i;
    EXPECT_EQ(rgb & 0xFFFFFFu, (uint32_t{colors[i][0]} << 16) | (uint32_t{colors[i][1]} << 8) | colors[i][2])
        << "point " << i;
  }
}

TEST(PcdIo, EmptyCloudIsAFileOfZeroPoints) {
  const std::string path = tempPath("empty.pcd");
  writePcd(path, {}, {});
  size_t body = 0;
  const std::vector<std::string> header = headerOf(readFile(path), body);
  EXPECT_NE(std::find(header.begin(), header.end(), "POINTS 0"), header.end());
  const PcdPoints c = readPcd(path);
  EXPECT_TRUE(c.points.empty());
  EXPECT_EQ(c.non_finite_dropped, 0u);
}

TEST(PcdIo, EveryEncodingRoundTripsExactly) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> coord(-50.0f, 50.0f);
  std::uniform_int_distribution<int> byte(0, 255);
  std::vector<Eigen::Vector3f> points(2000);
  std::vector<std::array<uint8_t, 3>> colors(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    points[i] = Eigen::Vector3f(coord(rng), coord(rng), coord(rng));
    colors[i] = {static_cast<uint8_t>(byte(rng)), static_cast<uint8_t>(byte(rng)), static_cast<uint8_t>(byte(rng))};
  }
  for (const auto& [name, encoding] : {std::pair{"ascii", PcdEncoding::kAscii}, std::pair{"binary", PcdEncoding::kBinary},
                                       std::pair{"compressed", PcdEncoding::kBinaryCompressed}}) {
    const std::string path = tempPath(std::string("round_") + name + ".pcd");
    writePcd(path, points, colors, encoding);
    const PcdPoints c = readPcd(path);
    ASSERT_EQ(c.points.size(), points.size()) << name;
    for (size_t i = 0; i < points.size(); ++i) {
      ASSERT_EQ(c.points[i], points[i]) << name << " point " << i;
      ASSERT_EQ(c.colors[i], colors[i]) << name << " point " << i;
    }
    writePcd(path, points, {}, encoding);
    const PcdPoints plain = readPcd(path);
    EXPECT_TRUE(plain.colors.empty()) << name;
    EXPECT_EQ(plain.points, points) << name;
  }
}

TEST(PcdIo, ErrorsNameTheFileAndTheProblem) {
  EXPECT_EQ(errorOf(tempPath("absent.pcd")), "cannot read " + tempPath("absent.pcd") + ": no such file");
  const std::string text = tempPath("hello.pcd");
  std::ofstream(text) << "hello\n";
  EXPECT_EQ(errorOf(text).rfind("cannot read " + text + " as PCD: pcl::PCDReader finds no PCD header", 0), 0u)
      << errorOf(text);
  const std::string noxyz = tempPath("noxyz.pcd");
  std::ofstream(noxyz) << "VERSION 0.7\nFIELDS a b c\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\n"
                          "DATA ascii\n1 2 3\n";
  EXPECT_EQ(errorOf(noxyz), noxyz + ": PCD FIELDS has no x, y and z");
  const std::string few = tempPath("few.pcd");
  std::ofstream(few) << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 1\nPOINTS 3\n"
                        "DATA binary\n"
                     << std::string(12, '\0');
  EXPECT_NE(errorOf(few).find("cannot read " + few + " as PCD"), std::string::npos) << errorOf(few);
  try {
    writePcd(tempPath("bad.pcd"), {{0, 0, 0}, {1, 1, 1}}, {{1, 2, 3}});
    ADD_FAILURE() << "2 points with 1 colour were written";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "cannot write " + tempPath("bad.pcd") + ": 2 points but 1 colours");
  }
  EXPECT_FALSE(std::filesystem::exists(tempPath("bad.pcd")));
}

}  // namespace
}  // namespace cenote::io
