// The message layer (io/bag/ros_messages.h) on CDR: every type it reads, decoded from the bytes
// Foxglove's ROS 2 serialiser wrote (tests/io/bag/gen, values in expected.json); the images and
// odometry of the MCAP and .db3 recordings opened through openRecording; the errors for damaged bytes.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "common/error.h"
#include "io/bag/recording.h"
#include "io/bag/ros_messages.h"
#include "tests/io/bag/ros2_test_data.h"

namespace cenote::io::test {
namespace {

namespace fs = std::filesystem;

// A CDR message of `type` as a recording hands it on, and its values in expected.json.
struct CdrMessage {
  CdrMessage(const std::string& name, const std::string& type) : bytes(cdrSample(name)), v(cdrValues(name)) {
    topic.name = "/" + name;
    topic.type = type;
    topic.encoding = MessageEncoding::kCdr;
    message.topic = &topic;
    message.data = bytes;
    message.file_offset = 4242;
  }
  Bytes bytes;
  const nlohmann::json& v;
  TopicInfo topic;
  RecordedMessage message;
};

void expectPose(const RosPose& p, const nlohmann::json& header, const std::string& child, const nlohmann::json& position,
                const nlohmann::json& orientation) {
  EXPECT_EQ(p.stamp_ns, stampOf(header));
  EXPECT_EQ(p.frame_id, header["frame_id"]);
  EXPECT_EQ(p.child_frame_id, child);
  int i = 0;
  for (const char* k : {"x", "y", "z"}) EXPECT_EQ(p.position[i++], position[k].get<double>()) << k;
  i = 0;
  for (const char* k : {"x", "y", "z", "w"}) EXPECT_EQ(p.orientation_xyzw[i++], orientation[k].get<double>()) << k;
}

void expectTransform(const RosPose& p, const nlohmann::json& t) {
  expectPose(p, t["header"], t["child_frame_id"], t["transform"]["translation"], t["transform"]["rotation"]);
}

TEST(CdrMessages, Image) {
  const CdrMessage m("image", "sensor_msgs/Image");
  const RosImage image = decodeImage(m.message);
  EXPECT_EQ(image.stamp_ns, stampOf(m.v["header"]));
  EXPECT_EQ(image.frame_id, "cam0");
  EXPECT_EQ(image.width, 4u);
  EXPECT_EQ(image.height, 3u);
  EXPECT_EQ(image.encoding, "mono8");
  EXPECT_EQ(image.is_bigendian, 0);
  EXPECT_EQ(image.step, 4u);
  EXPECT_EQ(Bytes(image.data.begin(), image.data.end()), m.v["data"].get<Bytes>());
}

TEST(CdrMessages, CompressedImage) {
  const CdrMessage m("compressed_image", "sensor_msgs/CompressedImage");
  const RosCompressedImage image = decodeCompressedImage(m.message);
  EXPECT_EQ(image.stamp_ns, stampOf(m.v["header"]));
  EXPECT_EQ(image.frame_id, "cam1");
  EXPECT_EQ(image.format, "jpeg");
  EXPECT_EQ(Bytes(image.data.begin(), image.data.end()), m.v["data"].get<Bytes>());
}

TEST(CdrMessages, CameraInfo) {
  const CdrMessage m("camera_info", "sensor_msgs/CameraInfo");
  const RosCameraInfo info = decodeCameraInfo(m.message);
  EXPECT_EQ(info.stamp_ns, stampOf(m.v["header"]));
  EXPECT_EQ(info.width, 4u);
  EXPECT_EQ(info.height, 3u);
  EXPECT_EQ(info.distortion_model, "plumb_bob");
  EXPECT_EQ(info.D, m.v["d"].get<std::vector<double>>());
  EXPECT_EQ(std::vector<double>(info.K.begin(), info.K.end()), m.v["k"].get<std::vector<double>>());
  EXPECT_EQ(std::vector<double>(info.R.begin(), info.R.end()), m.v["r"].get<std::vector<double>>());
  EXPECT_EQ(std::vector<double>(info.P.begin(), info.P.end()), m.v["p"].get<std::vector<double>>());
}

TEST(CdrMessages, OdometryPoseStampedTransformStampedAndTf) {
  {
    const CdrMessage m("odometry", "nav_msgs/Odometry");
    const std::optional<RosPose> p = decodePose(m.message);
    ASSERT_TRUE(p);
    expectPose(*p, m.v["header"], "cam0", m.v["pose"]["pose"]["position"], m.v["pose"]["pose"]["orientation"]);
  }
  {
    const CdrMessage m("pose_stamped", "geometry_msgs/PoseStamped");
    const std::optional<RosPose> p = decodePose(m.message);
    ASSERT_TRUE(p);
    expectPose(*p, m.v["header"], "", m.v["pose"]["position"], m.v["pose"]["orientation"]);
  }
  {
    const CdrMessage m("transform_stamped", "geometry_msgs/TransformStamped");
    const std::optional<RosPose> p = decodePose(m.message);
    ASSERT_TRUE(p);
    expectTransform(*p, m.v);
  }
  {
    const CdrMessage m("tf_message", "tf2_msgs/TFMessage");
    const std::optional<RosPose> first = decodePose(m.message, "world", "imu");
    ASSERT_TRUE(first);
    expectTransform(*first, m.v["transforms"][0]);
    const std::optional<RosPose> second = decodePose(m.message, "/imu", "cam0");
    ASSERT_TRUE(second);
    expectTransform(*second, m.v["transforms"][1]);
    EXPECT_FALSE(decodePose(m.message, "world", "cam0")) << "no such pair in the message";
  }
}

TEST(CdrMessages, DamagedBytesNameTopicOffsetTypeAndField) {
  CdrMessage m("image", "sensor_msgs/Image");
  m.bytes.resize(m.bytes.size() - 2);
  m.message.data = m.bytes;
  try {
    decodeImage(m.message);
    FAIL() << "expected an IoError";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()),
              "topic /image, message at byte 4242: sensor_msgs/Image.data: CDR message: sequence of 12 elements at "
              "byte 52 needs at least 12 bytes, 10 left");
  }
}

// A sequence count larger than the bytes left (a float64[] or a message array) is refused as it is read,
// before a vector of that many elements is allocated.
TEST(CdrMessages, SequenceLongerThanItsBytesIsRefusedBeforeItIsAllocated) {
  CdrMessage info("camera_info", "sensor_msgs/CameraInfo");
  const std::size_t d = 48;  // D's count: after the header, height, width and "plumb_bob" (padded to 4)
  ASSERT_EQ(info.bytes[d], info.v["d"].size());
  info.bytes[d] = info.bytes[d + 1] = info.bytes[d + 2] = 0xff;
  info.bytes[d + 3] = 0x7f;
  const std::size_t size = info.bytes.size();
  try {
    decodeCameraInfo(info.message);
    FAIL() << "expected an IoError";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()), "topic /camera_info, message at byte 4242: sensor_msgs/CameraInfo.D: CDR message: "
                                     "sequence of 2147483647 elements at byte 52 needs at least 2147483647 bytes, " +
                                         std::to_string(size - d - 4) + " left");
  }
  CdrMessage tf("tf_message", "tf2_msgs/TFMessage");
  ASSERT_EQ(tf.bytes[4], tf.v["transforms"].size());  // the count of transforms, first after the encapsulation
  tf.bytes[4] = tf.bytes[5] = tf.bytes[6] = tf.bytes[7] = 0xff;
  try {
    decodePose(tf.message, "world", "cam0");
    FAIL() << "expected an IoError";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()), "topic /tf_message, message at byte 4242: tf2_msgs/TFMessage.transforms: CDR message: "
                                     "sequence of 4294967295 elements at byte 8 needs at least 4294967295 bytes, " +
                                         std::to_string(tf.bytes.size() - 8) + " left");
  }
}

// The generator's images: 4x3 mono8, pixel k = (31 seed + 7 k) & 0xff, header stamps 5 ms before the
// log time (cam1's log times 1 us after cam0's); its odometry of step i at (0.5 i, -0.25 i, 1 + 0.125 i).
void expectDive(Recording& rec) {
  RecordedMessage m;
  int images = 0, odometry = 0;
  while (rec.next({"/cam0/image_raw", "/cam1/image_raw", "/odom"}, m)) {
    if (m.topic->name == "/odom") {
      const std::optional<RosPose> p = decodePose(m);
      ASSERT_TRUE(p);
      EXPECT_EQ(p->stamp_ns, m.log_time_ns - 5000000 - 2000) << "odometry " << odometry;
      EXPECT_EQ(p->child_frame_id, "base_link");
      EXPECT_EQ(p->position[0], 0.5 * odometry);
      EXPECT_EQ(p->position[2], 1.0 + 0.125 * odometry);
      EXPECT_DOUBLE_EQ(p->orientation_xyzw[3], std::cos(0.05 * odometry));  // JavaScript's cos, within 4 ulp
      ++odometry;
      continue;
    }
    const bool left = m.topic->name == "/cam0/image_raw";
    const RosImage image = decodeImage(m);
    const int seed = 2 * (images / 2) + (left ? 0 : 100);
    EXPECT_EQ(image.stamp_ns, m.log_time_ns - (left ? 5000000 : 5001000)) << m.topic->name;
    EXPECT_EQ(image.frame_id, left ? "cam0" : "cam1");
    ASSERT_EQ(image.data.size(), 12u);
    for (int k = 0; k < 12; ++k) EXPECT_EQ(image.data[k], (seed * 31 + k * 7) & 0xff) << m.topic->name << " pixel " << k;
    ++images;
  }
  EXPECT_EQ(images, 12);
  EXPECT_EQ(odometry, 12);
}

TEST(CdrMessages, ThroughOpenRecordingFromMcapAndDb3) {
  for (const fs::path& path : {kData / "dive_lz4.mcap", kData / "dive_nosummary.mcap", kData / "dive_db3",
                               kData / "dive_db3_cut", kData / "dive_db3" / "dive_db3_1.db3"}) {
    SCOPED_TRACE(path.string());
    const std::unique_ptr<Recording> rec = openRecording(path);
    if (path.filename() == "dive_db3_1.db3") {
      EXPECT_EQ(rec->topics().size(), 8u);
      continue;  // the second half alone
    }
    expectDive(*rec);
  }
}

}  // namespace
}  // namespace cenote::io::test
