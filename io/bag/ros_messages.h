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

/// The pose a message of a pose topic gives (isPoseType): Odometry, PoseStamped, TransformStamped;
/// of a TFMessage the transform from `parent` to `child` (leading '/' ignored), nullopt when the
/// message has none. `parent` and `child` also select within the other types when not empty: a
/// message whose frames differ is nullopt.
std::optional<RosPose> decodePose(const RecordedMessage& message, const std::string& parent = "",
                                  const std::string& child = "");

// ---------------------------------------------------------------------------------------------------
// Implementation of the parsers.

namespace detail {

// Runs `read` and adds "<type>.<field>: " to an IoError, field being what `read` last set.
template <class F>
auto withField(const char* type, const char*& field, F&& read) {
  try {
    return read();
  } catch (const IoError& e) {
    throw IoError(std::string(type) + "." + field + ": " + e.what());
  }
}

template <class Wire, std::size_t N>
void readDoubles(Wire& w, std::array<double, N>& out) {
  for (double& v : out) v = w.f64();
}

template <class Wire>
void readPose(Wire& w, RosPose& p) {
  for (double& v : p.position) v = w.f64();
  for (double& v : p.orientation_xyzw) v = w.f64();
}

}  // namespace detail

template <class Wire>
RosImage parseImage(Wire& w) {
  const char* field = "header";
  return detail::withField("sensor_msgs/Image", field, [&] {
    RosImage m;
    m.stamp_ns = w.headerStampNs(&m.frame_id);
    field = "height";
    m.height = w.u32();
    field = "width";
    m.width = w.u32();
    field = "encoding";
    m.encoding = w.str();
    field = "is_bigendian";
    m.is_bigendian = w.u8();
    field = "step";
    m.step = w.u32();
    field = "data";
    m.data = w.bytes(w.length());
    return m;
  });
}

template <class Wire>
RosCompressedImage parseCompressedImage(Wire& w) {
  const char* field = "header";
  return detail::withField("sensor_msgs/CompressedImage", field, [&] {
    RosCompressedImage m;
    m.stamp_ns = w.headerStampNs(&m.frame_id);
    field = "format";
    m.format = w.str();
    field = "data";
    m.data = w.bytes(w.length());
    return m;
  });
}

template <class Wire>
RosCameraInfo parseCameraInfo(Wire& w) {
  const char* field = "header";
  return detail::withField("sensor_msgs/CameraInfo", field, [&] {
    RosCameraInfo m;
    m.stamp_ns = w.headerStampNs(&m.frame_id);
    field = "height";
    m.height = w.u32();
    field = "width";
    m.width = w.u32();
    field = "distortion_model";
    m.distortion_model = w.str();
    field = "D";
    m.D.resize(w.length());
    for (double& v : m.D) v = w.f64();
    field = "K";
    detail::readDoubles(w, m.K);
    field = "R";
    detail::readDoubles(w, m.R);
    field = "P";
    detail::readDoubles(w, m.P);
    return m;  // binning and region of interest follow; cenote reads full-resolution images only
  });
}

template <class Wire>
RosPose parseOdometry(Wire& w) {
  const char* field = "header";
  return detail::withField("nav_msgs/Odometry", field, [&] {
    RosPose p;
    p.stamp_ns = w.headerStampNs(&p.frame_id);
    field = "child_frame_id";
    p.child_frame_id = w.str();
    field = "pose";
    detail::readPose(w, p);
    return p;  // the covariance and the twist follow
  });
}

template <class Wire>
RosPose parsePoseStamped(Wire& w) {
  const char* field = "header";
  return detail::withField("geometry_msgs/PoseStamped", field, [&] {
    RosPose p;
    p.stamp_ns = w.headerStampNs(&p.frame_id);
    field = "pose";
    detail::readPose(w, p);
    return p;
  });
}

template <class Wire>
RosPose parseTransformStamped(Wire& w) {
  const char* field = "header";
  return detail::withField("geometry_msgs/TransformStamped", field, [&] {
    RosPose p;
    p.stamp_ns = w.headerStampNs(&p.frame_id);
    field = "child_frame_id";
    p.child_frame_id = w.str();
    field = "transform";
    detail::readPose(w, p);
    return p;
  });
}

template <class Wire>
std::vector<RosPose> parseTfMessage(Wire& w) {
  const char* field = "transforms";
  return detail::withField("tf2_msgs/TFMessage", field, [&] {
    const std::uint32_t n = w.length();
    std::vector<RosPose> out;
    out.reserve(n);
    for (std::uint32_t i = 0; i < n; ++i) out.push_back(parseTransformStamped(w));
    return out;
  });
}

}  // namespace cenote::io
