// scalar_bytes.h: the numeric scalar types of binary point-cloud files (PLY properties, PCD fields)
// and the one decoder of such a scalar from a file's bytes.
// Threads: pure functions.
#pragma once

namespace cenote {

enum class ScalarType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

// Bytes of one scalar: 1, 2, 4 or 8.
int sizeOf(ScalarType type);

// The scalar of `type` at `src` (any alignment) as a double. `swap` reverses its bytes first: data
// of the other byte order than this host's (big-endian PLY on a little-endian machine).
double decodeScalar(const void* src, ScalarType type, bool swap = false);

}  // namespace cenote
