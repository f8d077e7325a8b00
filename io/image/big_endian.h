// big_endian.h: the byte order of PNG chunk fields and zlib's Adler-32 (most significant byte
// first), read and written by png_decoder.cpp, png_encoder.cpp and rle_deflate.cpp, and the PNG
// file signature they share.
// Threads: pure functions.
#pragma once

#include <array>
#include <cstdint>

namespace cenote::io {

inline constexpr std::array<uint8_t, 8> kPngSignature = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};

inline uint32_t loadBigEndian32(const uint8_t* p) {
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | uint32_t{p[3]};
}
inline void storeBigEndian32(uint8_t* p, uint32_t value) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(value >> (24 - 8 * i));
}

}  // namespace cenote::io
