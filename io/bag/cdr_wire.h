// cdr_wire.h: a reader of OMG CDR bytes (XCDR1, as ROS 2's middlewares write it), the serialisation of
// ROS 2 messages in MCAP and .db3 recordings, with the members every wire reader of io/bag/ros_messages.h
// has. Layout: a 4-byte encapsulation header (0x00 0x00 big-endian CDR, 0x00 0x01 little-endian CDR, then
// two option bytes), then the fields; each primitive is aligned to its own size counted from after the
// header; a string is a u32 length that counts its NUL,
// its bytes and the NUL; a sequence is a u32 element count, then the elements.
// Errors: IoError naming the field kind, its offset and the bytes left, e.g.
//   "CDR message: f64 at byte 44 needs 8 bytes, 3 left"; a sequence's count is checked against the
// bytes left before anything is allocated, so a corrupt count never allocates gigabytes.
// Threads: one reader per thread; it views the bytes it was given, which must outlive it.
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <span>
#include <string>

#include "common/error.h"

namespace cenote::io {

class CdrWire {
 public:
  /// @param data the whole serialised message, encapsulation header included.
  /// @throws IoError for fewer than 4 bytes or another encapsulation (parameter lists, XCDR2).
  explicit CdrWire(std::span<const std::uint8_t> data) : data_(data) {
    if (data_.size() < 4) fail("encapsulation header", 4);
    const std::uint8_t kind = data_[1];
    if (data_[0] != 0 || (kind != 0x00 && kind != 0x01)) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "%02x %02x", data_[0], data_[1]);
      throw IoError(std::string("CDR message: encapsulation ") + hex +
                    " is not plain CDR (00 00 big-endian, 00 01 little-endian); parameter lists and XCDR2 are not "
                    "read");
    }
    little_endian_ = kind == 0x01;
    pos_ = 4;
  }

  std::uint8_t u8() {
    need(1, "u8");
    return data_[pos_++];
  }
  std::uint32_t u32() { return scalar<std::uint32_t>("u32"); }
  std::int32_t i32() { return static_cast<std::int32_t>(scalar<std::uint32_t>("i32")); }
  float f32() {
    const std::uint32_t bits = scalar<std::uint32_t>("f32");
    float value;
    std::memcpy(&value, &bits, sizeof value);
    return value;
  }
  double f64() {
    const std::uint64_t bits = scalar<std::uint64_t>("f64");
    double value;
    std::memcpy(&value, &bits, sizeof value);
    return value;
  }

  /// A string: u32 length counting the terminating NUL (0 from some writers for ""), bytes, NUL.
  std::string str() {
    const std::uint32_t n = scalar<std::uint32_t>("string length");
    need(n, "string");
    const char* begin = reinterpret_cast<const char*>(data_.data() + pos_);
    std::size_t len = n;
    if (len > 0 && begin[len - 1] == '\0') --len;
    pos_ += n;
    return std::string(begin, len);
  }

  /// n raw bytes (a uint8[] or the payload of a sequence<uint8>), no alignment.
  std::span<const std::uint8_t> bytes(std::size_t n) {
    need(n, "byte array");
    const std::span<const std::uint8_t> out = data_.subspan(pos_, n);
    pos_ += n;
    return out;
  }

  /// The element count of a variable-size sequence. Each element takes at least one byte, so a count
  /// above the bytes left is damage, reported here before a caller allocates the elements.
  std::uint32_t length() {
    const std::uint32_t n = scalar<std::uint32_t>("sequence length");
    if (n > data_.size() - pos_) {
      throw IoError("CDR message: sequence of " + std::to_string(n) + " elements at byte " + std::to_string(pos_) +
                    " needs at least " + std::to_string(n) + " bytes, " + std::to_string(data_.size() - pos_) + " left");
    }
    return n;
  }

  /// builtin_interfaces/Time: i32 sec, u32 nanosec.
  std::int64_t stampNs() {
    const std::int64_t sec = i32();
    const std::int64_t nsec = u32();
    return sec * 1000000000 + nsec;
  }

  /// std_msgs/Header of ROS 2: stamp, frame_id (no seq).
  std::int64_t headerStampNs(std::string* frame_id) {
    const std::int64_t stamp_ns = stampNs();
    std::string frame = str();
    if (frame_id) *frame_id = std::move(frame);
    return stamp_ns;
  }

  /// Bytes read so far, header included.
  std::size_t offset() const { return pos_; }
  bool isLittleEndian() const { return little_endian_; }

 private:
  template <class T>
  T scalar(const char* what) {
    const std::size_t align = sizeof(T);
    const std::size_t body = pos_ - 4;  // alignment counts from after the encapsulation header
    const std::size_t padded = pos_ + (align - body % align) % align;
    if (padded > data_.size()) fail(what, sizeof(T));
    pos_ = padded;
    need(sizeof(T), what);
    T value;
    std::memcpy(&value, data_.data() + pos_, sizeof value);
    pos_ += sizeof(T);
    if (!little_endian_) value = swap(value);
    return value;
  }

  static std::uint32_t swap(std::uint32_t v) { return __builtin_bswap32(v); }
  static std::uint64_t swap(std::uint64_t v) { return __builtin_bswap64(v); }

  void need(std::size_t n, const char* what) const {
    if (n > data_.size() - pos_) fail(what, n);
  }

  [[noreturn]] void fail(const char* what, std::size_t n) const {
    throw IoError("CDR message: " + std::string(what) + " at byte " + std::to_string(pos_) + " needs " + std::to_string(n) +
                  " bytes, " + std::to_string(data_.size() - pos_) + " left");
  }

  std::span<const std::uint8_t> data_;
  std::size_t pos_ = 0;
  bool little_endian_ = true;
};

}  // namespace cenote::io
