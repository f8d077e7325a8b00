#include "common/scalar_bytes.h"

#include <algorithm>
#include <cstdint>
#include <cstring>

namespace cenote {
namespace {

template <typename T>
double load(const char* bytes) {
  T value;
  std::memcpy(&value, bytes, sizeof(T));
  return static_cast<double>(value);
}

}  // namespace

int sizeOf(ScalarType type) {
  switch (type) {
    case ScalarType::kInt8:
    case ScalarType::kUint8: return 1;
    case ScalarType::kInt16:
    case ScalarType::kUint16: return 2;
    case ScalarType::kInt32:
    case ScalarType::kUint32:
    case ScalarType::kFloat32: return 4;
    case ScalarType::kFloat64: return 8;
  }
  return 0;
}

double decodeScalar(const void* src, ScalarType type, bool swap) {
  char bytes[8];
  const int n = sizeOf(type);
  std::memcpy(bytes, src, n);
  if (swap) std::reverse(bytes, bytes + n);
  switch (type) {
    case ScalarType::kInt8: return load<int8_t>(bytes);
    case ScalarType::kUint8: return load<uint8_t>(bytes);
    case ScalarType::kInt16: return load<int16_t>(bytes);
    case ScalarType::kUint16: return load<uint16_t>(bytes);
    case ScalarType::kInt32: return load<int32_t>(bytes);
    case ScalarType::kUint32: return load<uint32_t>(bytes);
    case ScalarType::kFloat32: return load<float>(bytes);
    case ScalarType::kFloat64: return load<double>(bytes);
  }
  return 0.0;
}

}  // namespace cenote
