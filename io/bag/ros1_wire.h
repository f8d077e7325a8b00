// ros1_wire.h: the reader of ROS 1 serialised message bytes (roscpp_serialization): little-endian,
// packed (no alignment), strings and variable-size arrays prefixed by a u32 count, fixed-size arrays
// without one, time as u32 seconds + u32 nanoseconds, std_msgs/Header as u32 seq, time, string
// frame_id. One of the two wire readers the message parsers of ros_messages.h are templates over
// (the other: CdrWire, io/bag/cdr_wire.h).
// Every read throws IoError naming what ran out, the byte offset in the message and the message's
// size when the bytes run out; lengths are checked against the bytes left before anything is
// allocated, so a corrupt length never allocates gigabytes.
// Threads: one reader per thread; it only views the bytes, which must outlive it.
#pragma once

#include <cstdint>
#include <cstring>
#include <span>
#include <string>

#include "common/error.h"

namespace cenote::io {

class Ros1Wire {
 public:
  explicit Ros1Wire(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}

  std::uint8_t u8() { return take<std::uint8_t>("u8"); }
  std::uint32_t u32() { return take<std::uint32_t>("u32"); }
  std::int32_t i32() { return take<std::int32_t>("i32"); }
  float f32() { return take<float>("f32"); }
  double f64() { return take<double>("f64"); }
  std::string str() {
    const std::uint32_t n = length();
    const std::span<const std::uint8_t> b = bytes(n);
    return std::string(reinterpret_cast<const char*>(b.data()), b.size());
  }
  std::span<const std::uint8_t> bytes(std::size_t n) {
    need(n, "bytes");
    const std::span<const std::uint8_t> out = bytes_.subspan(pos_, n);
    pos_ += n;
    return out;
  }
  // The count of a variable-size array or string: each element takes at least one byte, so a
  // count above the bytes left is damage, reported here.
  std::uint32_t length() {
    const std::uint32_t n = u32();
    if (n > bytes_.size() - pos_) {
      throw IoError("ROS 1 message: length " + std::to_string(n) + " at byte " + std::to_string(pos_ - 4) +
                    " exceeds the " + std::to_string(bytes_.size() - pos_) + " bytes left of " +
                    std::to_string(bytes_.size()));
    }
    return n;
  }
  std::int64_t stampNs() {
    const std::uint32_t sec = u32();
    const std::uint32_t nsec = u32();
    return static_cast<std::int64_t>(sec) * 1000000000 + nsec;
  }
  std::int64_t headerStampNs(std::string* frame_id) {
    u32();  // seq
    const std::int64_t stamp = stampNs();
    std::string id = str();
    if (frame_id != nullptr) *frame_id = std::move(id);
    return stamp;
  }

  std::size_t position() const { return pos_; }
  std::size_t remaining() const { return bytes_.size() - pos_; }

 private:
  void need(std::size_t n, const char* what) const {
    if (n > bytes_.size() - pos_) {
      throw IoError(std::string("ROS 1 message: ") + what + " of " + std::to_string(n) + " bytes at byte " +
                    std::to_string(pos_) + " runs past its end (" + std::to_string(bytes_.size()) + " bytes)");
    }
  }
  template <class T>
  T take(const char* what) {
    need(sizeof(T), what);
    T value;
    std::memcpy(&value, bytes_.data() + pos_, sizeof(T));  // x86 and ARM are little-endian, as ROS 1 is
    pos_ += sizeof(T);
    return value;
  }

  std::span<const std::uint8_t> bytes_;
  std::size_t pos_ = 0;
};

}  // namespace cenote::io
