// CdrWire on CDR bytes written by Foxglove's ROS 2 serialiser (tests/io/bag/gen: one message of each
// type, its values in expected.json), read field by field as the ROS 2 definitions lay them out; and on
// hand-checked big-endian bytes; the exact errors for bytes that run out and foreign encapsulations.
#include "io/bag/cdr_wire.h"

#include <gtest/gtest.h>

#include "tests/io/bag/ros2_test_data.h"

namespace cenote::io::test {
namespace {

namespace fs = std::filesystem;

void expectHeader(CdrWire& w, const nlohmann::json& header) {
  std::string frame;
  EXPECT_EQ(w.headerStampNs(&frame), stampOf(header));
  EXPECT_EQ(frame, header["frame_id"]);
}

// A uint8[] field: its length, then that many bytes, the json's.
void expectByteArray(CdrWire& w, const nlohmann::json& want) {
  const std::uint32_t n = w.length();
  const std::span<const std::uint8_t> data = w.bytes(n);
  EXPECT_EQ(Bytes(data.begin(), data.end()), want.get<Bytes>());
}

void expectDoubles(CdrWire& w, const nlohmann::json& want, const char* field) {
  for (std::size_t i = 0; i < want.size(); ++i) EXPECT_EQ(w.f64(), want[i].get<double>()) << field << "[" << i << "]";
}

void expectPose(CdrWire& w, const nlohmann::json& pose) {  // geometry_msgs/Pose
  for (const char* k : {"x", "y", "z"}) EXPECT_EQ(w.f64(), pose["position"][k].get<double>()) << "position." << k;
  for (const char* k : {"x", "y", "z", "w"})
    EXPECT_EQ(w.f64(), pose["orientation"][k].get<double>()) << "orientation." << k;
}

void expectTransform(CdrWire& w, const nlohmann::json& t) {  // geometry_msgs/TransformStamped
  expectHeader(w, t["header"]);
  EXPECT_EQ(w.str(), t["child_frame_id"]);
  for (const char* k : {"x", "y", "z"}) EXPECT_EQ(w.f64(), t["transform"]["translation"][k].get<double>()) << k;
  for (const char* k : {"x", "y", "z", "w"}) EXPECT_EQ(w.f64(), t["transform"]["rotation"][k].get<double>()) << k;
}

// One sample message: its bytes, its values in expected.json, and a CdrWire at its start.
struct CdrSample {
  explicit CdrSample(const std::string& name) : bytes(cdrSample(name)), v(cdrValues(name)), w(bytes) {}
  const Bytes bytes;
  const nlohmann::json& v;
  CdrWire w;
};

TEST(CdrWire, ImageFromTheIndependentSerialiser) {
  CdrSample s("image");
  EXPECT_TRUE(s.w.isLittleEndian());
  expectHeader(s.w, s.v["header"]);
  EXPECT_EQ(s.w.u32(), s.v["height"].get<std::uint32_t>());
  EXPECT_EQ(s.w.u32(), s.v["width"].get<std::uint32_t>());
  EXPECT_EQ(s.w.str(), s.v["encoding"]);
  EXPECT_EQ(s.w.u8(), s.v["is_bigendian"].get<int>());
  EXPECT_EQ(s.w.u32(), s.v["step"].get<std::uint32_t>());
  expectByteArray(s.w, s.v["data"]);
  EXPECT_EQ(s.w.offset(), s.bytes.size());
}

TEST(CdrWire, CompressedImage) {
  CdrSample s("compressed_image");
  expectHeader(s.w, s.v["header"]);
  EXPECT_EQ(s.w.str(), s.v["format"]);
  expectByteArray(s.w, s.v["data"]);
  EXPECT_EQ(s.w.offset(), s.bytes.size());
}

TEST(CdrWire, CameraInfoDoublesAlignedAfterStrings) {
  CdrSample s("camera_info");
  expectHeader(s.w, s.v["header"]);
  EXPECT_EQ(s.w.u32(), 3u);
  EXPECT_EQ(s.w.u32(), 4u);
  EXPECT_EQ(s.w.str(), "plumb_bob");
  ASSERT_EQ(s.w.length(), 5u);
  expectDoubles(s.w, s.v["d"], "d");
  expectDoubles(s.w, s.v["k"], "k");
  expectDoubles(s.w, s.v["r"], "r");
  expectDoubles(s.w, s.v["p"], "p");
  EXPECT_EQ(s.w.u32(), 0u);  // binning
  EXPECT_EQ(s.w.u32(), 0u);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(s.w.u32(), 0u);  // roi
  EXPECT_EQ(s.w.u8(), 0);                                // roi.do_rectify
  EXPECT_EQ(s.w.offset(), s.bytes.size());
}

TEST(CdrWire, OdometryPoseStampedAndTransforms) {
  {
    CdrSample s("odometry");
    expectHeader(s.w, s.v["header"]);
    EXPECT_EQ(s.w.str(), s.v["child_frame_id"]);
    expectPose(s.w, s.v["pose"]["pose"]);
    expectDoubles(s.w, s.v["pose"]["covariance"], "pose.covariance");
    for (const char* part : {"linear", "angular"})
      for (const char* k : {"x", "y", "z"}) EXPECT_EQ(s.w.f64(), s.v["twist"]["twist"][part][k].get<double>());
    expectDoubles(s.w, s.v["twist"]["covariance"], "twist.covariance");
    EXPECT_EQ(s.w.offset(), s.bytes.size());
  }
  {
    CdrSample s("pose_stamped");
    expectHeader(s.w, s.v["header"]);
    expectPose(s.w, s.v["pose"]);
    EXPECT_EQ(s.w.offset(), s.bytes.size());
  }
  {
    CdrSample s("transform_stamped");
    expectTransform(s.w, s.v);
    EXPECT_EQ(s.w.offset(), s.bytes.size());
  }
  {
    CdrSample s("tf_message");
    ASSERT_EQ(s.w.length(), 2u);
    expectTransform(s.w, s.v["transforms"][0]);
    expectTransform(s.w, s.v["transforms"][1]);
    EXPECT_EQ(s.w.offset(), s.bytes.size());
  }
}

TEST(CdrWire, BigEndianBytesCheckedByHand) {
  // header 00 00 (CDR_BE), options; stamp sec = 2, nanosec = 5; frame_id "ab" (length 3 with its NUL);
  // one pad byte (byte 15 of the body to 16, a multiple of 8); f64 1.5 = 3f f8 00 .. 00
  const Bytes bytes = {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x05, 0x00, 0x00,
                       0x00, 0x03, 'a',  'b',  0x00, 0x00, 0x3f, 0xf8, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00};
  CdrWire w(bytes);
  EXPECT_FALSE(w.isLittleEndian());
  std::string frame;
  EXPECT_EQ(w.headerStampNs(&frame), 2000000005);
  EXPECT_EQ(frame, "ab");
  EXPECT_EQ(w.f64(), 1.5);
  EXPECT_EQ(w.offset(), bytes.size());
}

TEST(CdrWire, BytesThatRunOutAndForeignEncapsulations) {
  Bytes bytes = cdrSample("odometry");
  bytes.resize(bytes.size() - 3);
  CdrWire w(bytes);
  std::string frame;
  w.headerStampNs(&frame);
  w.str();
  try {
    for (int i = 0; i < 7 + 36 + 6 + 36; ++i) w.f64();
    FAIL() << "expected an IoError";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()),
              "CDR message: f64 at byte " + std::to_string(bytes.size() - 5) + " needs 8 bytes, 5 left");
  }
  try {
    CdrWire(Bytes{0x00, 0x03, 0x00, 0x00});
    FAIL() << "expected an IoError";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()),
              "CDR message: encapsulation 00 03 is not plain CDR (00 00 big-endian, 00 01 little-endian); parameter "
              "lists and XCDR2 are not read");
  }
  EXPECT_THROW(CdrWire(Bytes{0x00, 0x01}), IoError);
}

}  // namespace
}  // namespace cenote::io::test
