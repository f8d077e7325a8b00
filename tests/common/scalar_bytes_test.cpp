#include "common/scalar_bytes.h"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstring>

namespace cenote {
namespace {

// The bytes of `v` in this host's order, after one leading byte so that the scalar is unaligned.
template <typename T>
std::array<char, 9> unalignedBytesOf(T v) {
  std::array<char, 9> bytes{};
  std::memcpy(bytes.data() + 1, &v, sizeof(T));
  return bytes;
}

template <typename T>
double decoded(T v, ScalarType type) {
  return decodeScalar(unalignedBytesOf(v).data() + 1, type);
}

TEST(ScalarBytes, SizesOfEveryType) {
  EXPECT_EQ(sizeOf(ScalarType::kInt8), 1);
  EXPECT_EQ(sizeOf(ScalarType::kUint8), 1);
  EXPECT_EQ(sizeOf(ScalarType::kInt16), 2);
  EXPECT_EQ(sizeOf(ScalarType::kUint16), 2);
  EXPECT_EQ(sizeOf(ScalarType::kInt32), 4);
  EXPECT_EQ(sizeOf(ScalarType::kUint32), 4);
  EXPECT_EQ(sizeOf(ScalarType::kFloat32), 4);
  EXPECT_EQ(sizeOf(ScalarType::kFloat64), 8);
}

TEST(ScalarBytes, DecodesEveryTypeAtAnyAlignment) {
  EXPECT_EQ(decoded<int8_t>(-128, ScalarType::kInt8), -128.0);
  EXPECT_EQ(decoded<uint8_t>(255, ScalarType::kUint8), 255.0);
  EXPECT_EQ(decoded<int16_t>(-32768, ScalarType::kInt16), -32768.0);
  EXPECT_EQ(decoded<uint16_t>(65535, ScalarType::kUint16), 65535.0);
  EXPECT_EQ(decoded<int32_t>(-2147483647 - 1, ScalarType::kInt32), -2147483648.0);
  EXPECT_EQ(decoded<uint32_t>(4294967295u, ScalarType::kUint32), 4294967295.0);
  EXPECT_EQ(decoded<float>(-1.5f, ScalarType::kFloat32), -1.5);
  EXPECT_EQ(decoded<double>(0.1, ScalarType::kFloat64), 0.1);
}

TEST(ScalarBytes, SwapReadsTheOtherByteOrder) {
  const char big_endian_int16[] = {0x01, 0x02};  // 0x0102 = 258 stored big-endian
  const char little_endian_int16[] = {0x02, 0x01};
  EXPECT_EQ(decodeScalar(little_endian_int16, ScalarType::kInt16), 258.0);
  EXPECT_EQ(decodeScalar(big_endian_int16, ScalarType::kInt16, true), 258.0);
  const char big_endian_float[] = {0x3f, static_cast<char>(0xc0), 0x00, 0x00};  // 1.5f
  EXPECT_EQ(decodeScalar(big_endian_float, ScalarType::kFloat32, true), 1.5);
}

}  // namespace
}  // namespace cenote
