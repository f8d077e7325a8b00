// ros_messages.h: the ROS messages cenote reads from a recording, as plain structs, and their
// parsers, written once as templates over a wire reader so that ROS 1 bytes (Ros1Wire,
// io/bag/ros1_wire.h) and ROS 2 CDR bytes (CdrWire, io/bag/cdr_wire.h) go through the same code.
//   sensor_msgs/Image, sensor_msgs/CompressedImage, sensor_msgs/CameraInfo,
//   nav_msgs/Odometry, geometry_msgs/PoseStamped, geometry_msgs/TransformStamped, tf2_msgs/TFMessage
// A wire reader has: u8(), u32(), i32(), f32(), f64(), str(), bytes(n), length() (the count of a
// variable-size array), stampNs() and headerStampNs(&frame_id); each throws IoError when the bytes
// run out. The parsers add the message type and field to that error; decode*() add the topic and
// the file offset.
// Units: nanoseconds of the recording's clock; metres; poses as a translation and a Hamilton unit
// quaternion (x y z w), T_parent_child (frame_id <- child_frame_id), as ROS defines them.
// Threads: free functions over the bytes given; views (RosImage::data, RosCompressedImage::data) are
// valid as long as those bytes (RecordedMessage::data: until the next Recording::next()).
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "common/error.h"
#include "io/bag/recording.h"

namespace cenote::io {

/// sensor_msgs/Image. `data` views the message's bytes: `height` rows of `step` bytes.
struct RosImage {
  std::int64_t stamp_ns = 0;
  std::string frame_id;
  std::uint32_t width = 0, height = 0;
  std::string encoding;  ///< "mono8", "bgr8", "rgb8", "bayer_rggb8", ...
  std::uint8_t is_bigendian = 0;
  std::uint32_t step = 0;  ///< bytes per row
  std::span<const std::uint8_t> data;
};

/// sensor_msgs/CompressedImage. `format` is what the driver wrote ("jpeg", "png", "mono8; jpeg
/// compressed bgr8"); the bytes themselves say what they are (io/bag/ros_image.h reads them).
struct RosCompressedImage {
  std::int64_t stamp_ns = 0;
  std::string frame_id;
  std::string format;
  std::span<const std::uint8_t> data;
};

/// sensor_msgs/CameraInfo: K (3x3), R (3x3, the rectifying rotation), P (3x4, the projection of the
/// rectified camera; for the right camera of a stereo pair P[3] = -fx' * baseline), row-major.
struct RosCameraInfo {
  std::int64_t stamp_ns = 0;
  std::string frame_id;
  std::uint32_t width = 0, height = 0;
  std::string distortion_model;  ///< "plumb_bob", "rational_polynomial", "equidistant", ...
  std::vector<double> D;
  std::array<double, 9> K{};
  std::array<double, 9> R{};
  std::array<double, 12> P{};
};

/// A pose from nav_msgs/Odometry, geometry_msgs/PoseStamped, geometry_msgs/TransformStamped or one
/// transform of a tf2_msgs/TFMessage: child_frame_id's pose in frame_id (PoseStamped has no child:
/// empty).
struct RosPose {
  std::int64_t stamp_ns = 0;
  std::string frame_id;
  std::string child_frame_id;
  std::array<double, 3> position{};
  std::array<double, 4> orientation_xyzw{0.0, 0.0, 0.0, 1.0};

  /// T_frame_child. The quaternion is normalised; a zero or non-finite one throws Error.
  Eigen::Isometry3d transform() const;
};

// Parsers of one message each; @throws IoError "sensor_msgs/Image.step: ..." when the bytes run out.
template <class Wire>
RosImage parseImage(Wire& w);
template <class Wire>
RosCompressedImage parseCompressedImage(Wire& w);
template <class Wire>
RosCameraInfo parseCameraInfo(Wire& w);
template <class Wire>
RosPose parseOdometry(Wire& w);
template <class Wire>
RosPose parsePoseStamped(Wire& w);
template <class Wire>
RosPose parseTransformStamped(Wire& w);
template <class Wire>
std::vector<RosPose> parseTfMessage(Wire& w);

/// The types a pose topic may have.
bool isPoseType(const std::string& type);

// A message of a recording decoded by its topic's encoding (ROS 1 or CDR).
// @throws Error when the topic's type is not the one named (the topic and both types named);
//         IoError naming the topic, type, field and file offset when the bytes are damaged.
RosImage decodeImage(const RecordedMessage& message);
RosCompressedImage decodeCompressedImage(const RecordedMessage& message);
RosCameraInfo decodeCameraInfo(const RecordedMessage& message);
// The header stamp of a message whose first field is a std_msgs/Header (sensor_msgs/Image,
// CompressedImage, CameraInfo, ...), read without parsing or copying the rest.
std::int64_t decodeHeaderStampNs(const RecordedMessage& message);

/// The pose a message of a pose topic gives (isPoseType): Odometry, PoseStamped, TransformStamped;
/// of a TFMessage the transform from `parent` to `child` (leading '/' ignored), nullopt when the
/// message has none. `parent` and `child` also select within the other types when not empty: a
/// message whose frames differ is nullopt.
std::optional<RosPose> decodePose(const RecordedMessage& message, const std::string& parent = "",
                                  const std::string& child = "");

// ---------------------------------------------------------------------------------------------------
// Implementation of the parsers.

namespace detail {

// A wire reader that names the field being read: an IoError from `w` becomes
// "<type>.<field>: <what>" (e.g. "sensor_msgs/Image.step: ROS 1 message: u32 of 4 bytes ...").
template <class Wire>
class FieldReader {
 public:
  FieldReader(Wire& w, const char* type) : w_(w), type_(type) {}

  // Runs `read` with the field named `field`.
  template <class F>
  auto read(const char* field, F&& read) {
    try {
      return read();
    } catch (const IoError& e) {
      throw IoError(std::string(type_) + "." + field + ": " + e.what());
    }
  }

  std::int64_t header(std::string* frame_id) {
    return read("header", [&] { return w_.headerStampNs(frame_id); });
  }
  std::uint8_t u8(const char* field) {
    return read(field, [&] { return w_.u8(); });
  }
  std::uint32_t u32(const char* field) {
    return read(field, [&] { return w_.u32(); });
  }
  std::string str(const char* field) {
    return read(field, [&] { return w_.str(); });
  }
  // A variable-size byte array (uint8[]).
  std::span<const std::uint8_t> bytes(const char* field) {
    return read(field, [&] { return w_.bytes(w_.length()); });
  }
  // A variable-size array of doubles (float64[]).
  std::vector<double> doubles(const char* field) {
    return read(field, [&] {
      std::vector<double> out(w_.length());
      for (double& v : out) v = w_.f64();
      return out;
    });
  }
  // A fixed-size array of doubles (float64[N]).
  template <std::size_t N>
  void doubles(const char* field, std::array<double, N>& out) {
    read(field, [&] { readDoubles(out); });
  }
  // The std_msgs/Header, then the image size (uint32 height, uint32 width) that sensor_msgs/Image
  // and sensor_msgs/CameraInfo both begin with.
  template <class Message>
  void stampedSize(Message& m) {
    m.stamp_ns = header(&m.frame_id);
    m.height = u32("height");
    m.width = u32("width");
  }
  // geometry_msgs/Pose or geometry_msgs/Transform: a translation and a quaternion x y z w.
  void pose(const char* field, RosPose& p) {
    read(field, [&] {
      readDoubles(p.position);
      readDoubles(p.orientation_xyzw);
    });
  }

 private:
  template <std::size_t N>
  void readDoubles(std::array<double, N>& out) {
    for (double& v : out) v = w_.f64();
  }

  Wire& w_;
  const char* type_;
};

// The messages that carry one stamped pose: a header, a child frame id when `has_child`, then the
// pose or transform named `pose_field` (nav_msgs/Odometry, geometry_msgs/PoseStamped and
// geometry_msgs/TransformStamped begin alike).
template <class Wire>
RosPose parseStampedPose(Wire& w, const char* type, bool has_child, const char* pose_field) {
  FieldReader<Wire> r(w, type);
  RosPose p;
  p.stamp_ns = r.header(&p.frame_id);
  if (has_child) p.child_frame_id = r.str("child_frame_id");
  r.pose(pose_field, p);
  return p;
}

}  // namespace detail

template <class Wire>
RosImage parseImage(Wire& w) {
  detail::FieldReader<Wire> r(w, "sensor_msgs/Image");
  RosImage m;
  r.stampedSize(m);
  m.encoding = r.str("encoding");
  m.is_bigendian = r.u8("is_bigendian");
  m.step = r.u32("step");
  m.data = r.bytes("data");
  return m;
}

template <class Wire>
RosCompressedImage parseCompressedImage(Wire& w) {
  detail::FieldReader<Wire> r(w, "sensor_msgs/CompressedImage");
  RosCompressedImage m;
  m.stamp_ns = r.header(&m.frame_id);
  m.format = r.str("format");
  m.data = r.bytes("data");
  return m;
}

template <class Wire>
RosCameraInfo parseCameraInfo(Wire& w) {
  detail::FieldReader<Wire> r(w, "sensor_msgs/CameraInfo");
  RosCameraInfo m;
  r.stampedSize(m);
  m.distortion_model = r.str("distortion_model");
  m.D = r.doubles("D");
  r.doubles("K", m.K);
  r.doubles("R", m.R);
  r.doubles("P", m.P);
  return m;  // binning and region of interest follow; cenote reads full-resolution images only
}

template <class Wire>
RosPose parseOdometry(Wire& w) {
  return detail::parseStampedPose(w, "nav_msgs/Odometry", true, "pose");  // the covariance and the twist follow
}

template <class Wire>
RosPose parsePoseStamped(Wire& w) {
  return detail::parseStampedPose(w, "geometry_msgs/PoseStamped", false, "pose");
}

template <class Wire>
RosPose parseTransformStamped(Wire& w) {
  return detail::parseStampedPose(w, "geometry_msgs/TransformStamped", true, "transform");
}

template <class Wire>
std::vector<RosPose> parseTfMessage(Wire& w) {
  detail::FieldReader<Wire> r(w, "tf2_msgs/TFMessage");
  return r.read("transforms", [&] {
    const std::uint32_t n = w.length();
    std::vector<RosPose> out;
    out.reserve(n);
    for (std::uint32_t i = 0; i < n; ++i) out.push_back(parseTransformStamped(w));
    return out;
  });
}

}  // namespace cenote::io
