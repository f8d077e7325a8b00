// block_bits.h: helpers of OccupancyMap over a block's 512-bit masks and block orders, apart from
// the grid so that they need no OpenVDB header.
// Units: voxel and block indices. Threads: pure functions.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>

#include "mapping/voxel_types.h"

namespace cenote::mapping::detail {

// Bounding box of the set bits of a block's 512-bit mask (word w holds x = w; bit y * 8 + z).
inline VoxelBox boxOfBits(const BlockIndex& block, const std::array<uint64_t, 8>& bits) {
  VoxelBox box;
  uint64_t any = 0;
  int x_min = 8, x_max = -1;
  for (int w = 0; w < 8; ++w) {
    if (bits[w] == 0) continue;
    any |= bits[w];
    x_min = std::min(x_min, w);
    x_max = w;
  }
  if (any == 0) return box;
  uint8_t z_bits = 0;
  int y_min = 8, y_max = -1;
  for (int y = 0; y < 8; ++y) {
    const uint8_t row = static_cast<uint8_t>(any >> (8 * y));
    if (row == 0) continue;
    z_bits |= row;
    y_min = std::min(y_min, y);
    y_max = y;
  }
  const VoxelIndex base = block * kBlockSide;
  box.min = base + VoxelIndex(x_min, y_min, __builtin_ctz(z_bits));
  box.max = base + VoxelIndex(x_max, y_max, 31 - __builtin_clz(z_bits));
  return box;
}

// The order in which a standard FloatTree (internal nodes of 32^3 and 16^3 children: 4096^3 and
// 128^3 voxels) visits its leaves, which knownBlocks() kept before the map's tree got smaller
// internal nodes: node origins lexicographically, then children x-major inside each node. Keeps
// every consumer's block order (and so its results, e.g. frontier cluster numbering) unchanged.
// As one integer per block, sorted once (a block lies within +-2^20 on each axis, so x >> 9 within
// +-2^11): the top-level node's x, y, z (12 bits each, biased), then the 16^3 node's child index
// (5 bits per axis), then the leaf's (4 bits per axis); 63 bits.
inline uint64_t floatTreeOrderKey(const BlockIndex& b) {
  constexpr int64_t kBias = 1 << 11;
  uint64_t key = 0;
  for (int k = 0; k < 3; ++k) key = (key << 12) | static_cast<uint64_t>((b[k] >> 9) + kBias);
  for (int k = 0; k < 3; ++k) key = (key << 5) | static_cast<uint64_t>((b[k] >> 4) & 31);
  for (int k = 0; k < 3; ++k) key = (key << 4) | static_cast<uint64_t>(b[k] & 15);
  return key;
}
inline BlockIndex blockOfFloatTreeOrderKey(uint64_t key) {
  constexpr int64_t kBias = 1 << 11;
  BlockIndex b;
  for (int k = 0; k < 3; ++k) {
    const int64_t top = static_cast<int64_t>((key >> (51 - 12 * k)) & 4095) - kBias;
    const int64_t node = static_cast<int64_t>((key >> (22 - 5 * k)) & 31);
    const int64_t leaf = static_cast<int64_t>((key >> (8 - 4 * k)) & 15);
    b[k] = static_cast<int>(top * 512 + node * 16 + leaf);
  }
  return b;
}

}  // namespace cenote::mapping::detail
