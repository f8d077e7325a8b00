// output_growth.h: how the decoders of what recordings hold compressed (ROS 1 bag chunks in bz2 or
// LZ4, MCAP chunks, zstd messages) size their output without trusting a size field. A declared size
// is as damaged as the rest of a file can be: a gigabyte declared by a hundred bytes must not be
// allocated before the data decode to it. So an output buffer starts at the declared size only up to
// kPresizeRatio times the compressed bytes, and doubles as the data decode (a chunk that does
// compress further costs a few reallocations).
#pragma once

#include <algorithm>
#include <cstdint>

namespace cenote::io::detail {

inline constexpr std::uint64_t kPresizeRatio = 64;
inline constexpr std::uint64_t kMinOutputBytes = std::uint64_t{1} << 16;

/// The first size of the output of `stored` compressed bytes that say they decode to `declared`.
inline std::uint64_t initialOutputBytes(std::uint64_t declared, std::uint64_t stored, std::uint64_t max_bytes) {
  return std::min(max_bytes, std::max(std::min(declared, kPresizeRatio * stored), kMinOutputBytes));
}

/// The next size of a full output buffer of `size` bytes.
inline std::uint64_t grownOutputBytes(std::uint64_t size, std::uint64_t max_bytes) {
  return std::min(max_bytes, std::max(2 * size, kMinOutputBytes));
}

}  // namespace cenote::io::detail
