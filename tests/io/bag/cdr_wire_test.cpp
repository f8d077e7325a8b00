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

TEST(CdrWire, ImageFromTheIndependentSerialiser) {
  const Bytes bytes = cdrSample("image");
  const nlohmann::json& v = cdrValues("image");
  CdrWire w(bytes);
  EXPECT_TRUE(w.isLittleEndian());
  expectHeader(w, v["header"]);
  EXPECT_EQ(w.u32(), v["height"].get<std::uint32_t>());
  EXPECT_EQ(w.u32(), v["width"].get<std::uint32_t>());
  EXPECT_EQ(w.str(), v["encoding"]);
  EXPECT_EQ(w.u8(), v["is_bigendian"].get<int>());
  EXPECT_EQ(w.u32(), v["step"].get<std::uint32_t>());
  expectByteArray(w, v["data"]);
  EXPECT_EQ(w.offset(), bytes.size());
}

TEST(CdrWire, CompressedImage) {
  const Bytes bytes = cdrSample("compressed_image");
  const nlohmann::json& v = cdrValues("compressed_image");
  CdrWire w(bytes);
  expectHeader(w, v["header"]);
  EXPECT_EQ(w.str(), v["format"]);
  expectByteArray(w, v["data"]);
  EXPECT_EQ(w.offset(), bytes.size());
}

TEST(CdrWire, CameraInfoDoublesAlignedAfterStrings) {
  const Bytes bytes = cdrSample("camera_info");
  const nlohmann::json& v = cdrValues("camera_info");
  CdrWire w(bytes);
  expectHeader(w, v["header"]);
  EXPECT_EQ(w.u32(), 3u);
  EXPECT_EQ(w.u32(), 4u);
  EXPECT_EQ(w.str(), "plumb_bob");
  ASSERT_EQ(w.length(), 5u);
  expectDoubles(w, v["d"], "d");
  expectDoubles(w, v["k"], "k");
  expectDoubles(w, v["r"], "r");
  expectDoubles(w, v["p"], "p");
  EXPECT_EQ(w.u32(), 0u);  // binning
  EXPECT_EQ(w.u32(), 0u);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(w.u32(), 0u);  // roi
  EXPECT_EQ(w.u8(), 0);                                // roi.do_rectify
  EXPECT_EQ(w.offset(), bytes.size());
}

TEST(CdrWire, OdometryPoseStampedAndTransforms) {
  {
    const Bytes bytes = cdrSample("odometry");
    const nlohmann::json& v = cdrValues("odometry");
    CdrWire w(bytes);
    expectHeader(w, v["header"]);
    EXPECT_EQ(w.str(), v["child_frame_id"]);
    expectPose(w, v["pose"]["pose"]);
    expectDoubles(w, v["pose"]["covariance"], "pose.covariance");
    for (const char* part : {"linear", "angular"})
      for (const char* k : {"x", "y", "z"}) EXPECT_EQ(w.f64(), v["twist"]["twist"][part][k].get<double>());
    expectDoubles(w, v["twist"]["covariance"], "twist.covariance");
    EXPECT_EQ(w.offset(), bytes.size());
  }
  {
    const Bytes bytes = cdrSample("pose_stamped");
    CdrWire w(bytes);
    expectHeader(w, cdrValues("pose_stamped")["header"]);
    expectPose(w, cdrValues("pose_stamped")["pose"]);
    EXPECT_EQ(w.offset(), bytes.size());
  }
  {
    const Bytes bytes = cdrSample("transform_stamped");
    CdrWire w(bytes);
    expectTransform(w, cdrValues("transform_stamped"));
    EXPECT_EQ(w.offset(), bytes.size());
  }
  {
    const Bytes bytes = cdrSample("tf_message");
    const nlohmann::json& v = cdrValues("tf_message");
    CdrWire w(bytes);
    ASSERT_EQ(w.length(), 2u);
    expectTransform(w, v["transforms"][0]);
    expectTransform(w, v["transforms"][1]);
    EXPECT_EQ(w.offset(), bytes.size());
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
