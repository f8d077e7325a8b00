#include "io/bag/ros_messages.h"

#include <cmath>
#include <type_traits>

#include "io/bag/cdr_wire.h"
#include "io/bag/ros1_wire.h"

namespace cenote::io {
namespace {

void expectType(const RecordedMessage& m, const char* type) {
  if (m.topic == nullptr) throw Error(std::string("ROS message without a topic, expected ") + type);
  if (m.topic->type != type) {
    throw Error("topic " + m.topic->name + " has type " + m.topic->type + ", expected " + type);
  }
}

// Parses the message with the wire of its topic's encoding, adding the topic and offset to errors.
template <class Parse>
auto decode(const RecordedMessage& m, Parse&& parse) {
  try {
    if (m.topic->encoding == MessageEncoding::kCdr) {
      CdrWire wire(m.data);
      return parse(wire);
    }
    Ros1Wire wire(m.data);
    return parse(wire);
  } catch (const IoError& e) {
    throw IoError("topic " + m.topic->name + ", message at byte " + std::to_string(m.file_offset) + ": " + e.what());
  }
}

std::string stripSlash(const std::string& frame) { return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame; }

bool framesMatch(const RosPose& p, const std::string& parent, const std::string& child) {
  return (parent.empty() || stripSlash(p.frame_id) == stripSlash(parent)) &&
         (child.empty() || stripSlash(p.child_frame_id) == stripSlash(child));
}

}  // namespace

Eigen::Isometry3d RosPose::transform() const {
  const Eigen::Quaterniond q(orientation_xyzw[3], orientation_xyzw[0], orientation_xyzw[1], orientation_xyzw[2]);
  const double norm = q.norm();
  if (!std::isfinite(norm) || norm < 1e-9 || !std::isfinite(position[0] + position[1] + position[2])) {
    throw Error("pose of " + (child_frame_id.empty() ? frame_id : child_frame_id) + " at " + std::to_string(stamp_ns) +
                " ns: quaternion or position is zero or not finite");
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(position[0], position[1], position[2]);
  return T;
}

bool isPoseType(const std::string& type) {
  return type == "nav_msgs/Odometry" || type == "geometry_msgs/PoseStamped" || type == "geometry_msgs/TransformStamped" ||
         type == "tf2_msgs/TFMessage";
}

RosImage decodeImage(const RecordedMessage& message) {
  expectType(message, "sensor_msgs/Image");
  return decode(message, [](auto& w) { return parseImage(w); });
}

RosCompressedImage decodeCompressedImage(const RecordedMessage& message) {
  expectType(message, "sensor_msgs/CompressedImage");
  return decode(message, [](auto& w) { return parseCompressedImage(w); });
}

std::int64_t decodeHeaderStampNs(const RecordedMessage& message) {
  return decode(message, [&](auto& w) {
    detail::FieldReader<std::decay_t<decltype(w)>> r(w, message.topic->type.c_str());
    return r.header(nullptr);
  });
}

RosCameraInfo decodeCameraInfo(const RecordedMessage& message) {
  expectType(message, "sensor_msgs/CameraInfo");
  return decode(message, [](auto& w) { return parseCameraInfo(w); });
}

std::optional<RosPose> decodePose(const RecordedMessage& message, const std::string& parent, const std::string& child) {
  if (message.topic == nullptr) throw Error("ROS message without a topic, expected a pose");
  const std::string& type = message.topic->type;
  std::optional<RosPose> pose;
  if (type == "nav_msgs/Odometry") {
    pose = decode(message, [](auto& w) { return parseOdometry(w); });
  } else if (type == "geometry_msgs/PoseStamped") {
    pose = decode(message, [](auto& w) { return parsePoseStamped(w); });
    if (!child.empty()) pose->child_frame_id = child;  // PoseStamped names no child: it is the one asked for
  } else if (type == "geometry_msgs/TransformStamped") {
    pose = decode(message, [](auto& w) { return parseTransformStamped(w); });
  } else if (type == "tf2_msgs/TFMessage") {
    const std::vector<RosPose> all = decode(message, [](auto& w) { return parseTfMessage(w); });
    for (const RosPose& p : all) {
      if (framesMatch(p, parent, child)) return p;
    }
    return std::nullopt;
  } else {
    throw Error("topic " + message.topic->name + " has type " + type +
                ", not a pose (nav_msgs/Odometry, geometry_msgs/PoseStamped, geometry_msgs/TransformStamped or "
                "tf2_msgs/TFMessage)");
  }
  if (!framesMatch(*pose, parent, child)) return std::nullopt;
  return pose;
}

}  // namespace cenote::io
