// frontier_bits.h: bit-parallel operations on the 512-bit voxel mask of one 8x8x8 block, for the
// frontier map: 26-neighbour dilation, the 26-connected pieces of a block's mask, the six face
// layers of a piece and whether pieces of two neighbouring blocks touch.
// Layout (the map's, OpenVDB leaf order): word x (0..7), bit y * 8 + z. Face layers are 8x8
// masks over the two other axes in increasing order, bit u * 8 + w: face x -> (y, z), face y ->
// (x, z), face z -> (x, y). Threads: plain functions.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "mapping/voxel_types.h"

namespace cenote::mapping::detail {

using BlockMask = std::array<uint64_t, 8>;  // bit offsetInBlock(ijk)

inline constexpr uint64_t kLowBitOfEachByte = 0x0101010101010101ull;    // z = 0 (or w = 0) of each row
inline constexpr uint64_t kHighBitOfEachByte = kLowBitOfEachByte << 7;  // z = 7 (or w = 7)

inline bool isEmpty(const BlockMask& m) { return (m[0] | m[1] | m[2] | m[3] | m[4] | m[5] | m[6] | m[7]) == 0; }

// Dilation by one within an 8x8 layer (bit u * 8 + w) along w, and along u.
inline uint64_t dilateLow(uint64_t m) { return m | ((m << 1) & ~kLowBitOfEachByte) | ((m >> 1) & ~kHighBitOfEachByte); }
inline uint64_t dilateHigh(uint64_t m) { return m | (m << 8) | (m >> 8); }

// The voxels of the block within one voxel (26-neighbourhood) of m, m included.
inline BlockMask dilate26(const BlockMask& m) {
  uint64_t yz[8];
  for (int x = 0; x < 8; ++x) yz[x] = dilateHigh(dilateLow(m[x]));
  BlockMask out;
  for (int x = 0; x < 8; ++x) out[x] = yz[x] | (x > 0 ? yz[x - 1] : 0) | (x < 7 ? yz[x + 1] : 0);
  return out;
}

// Appends the 26-connected pieces of `bits` to `out`, in the order of their lowest bit.
inline void appendPieces(BlockMask bits, std::vector<BlockMask>& out) {
  for (int w = 0; w < 8; ++w) {
    while (bits[w] != 0) {
      BlockMask piece{};
      piece[w] = bits[w] & (~bits[w] + 1);  // lowest bit
      while (true) {
        const BlockMask grown = dilate26(piece);
        bool changed = false;
        for (int x = 0; x < 8; ++x) {
          const uint64_t next = grown[x] & bits[x];
          changed |= next != piece[x];
          piece[x] = next;
        }
        if (!changed) break;
      }
      for (int x = 0; x < 8; ++x) bits[x] &= ~piece[x];
      out.push_back(piece);
    }
  }
}

// Face layers, index 2 * axis for the face at coordinate 7, 2 * axis + 1 for coordinate 0.
struct FaceLayers {
  std::array<uint64_t, 6> layer{};
};

// Bits y * 8 + c (y = 0..7) of a word, as bit y of a byte.
inline uint64_t gatherZ(uint64_t word, int c) { return (((word >> c) & kLowBitOfEachByte) * 0x0102040810204080ull) >> 56; }

inline FaceLayers faceLayers(const BlockMask& m) {
  FaceLayers f;
  f.layer[0] = m[7];
  f.layer[1] = m[0];
  for (int x = 0; x < 8; ++x) {
    f.layer[2] |= ((m[x] >> 56) & 0xFF) << (8 * x);
    f.layer[3] |= (m[x] & 0xFF) << (8 * x);
    f.layer[4] |= gatherZ(m[x], 7) << (8 * x);
    f.layer[5] |= gatherZ(m[x], 0) << (8 * x);
  }
  return f;
}

// Whether a voxel of piece p (face layers) and a voxel of piece q, in the block offset by e
// (each coordinate -1, 0 or 1, not all 0) from p's, are 26-neighbours. Only the layers facing
// each other matter: restricted to the shared edge or corner where e has more than one nonzero
// coordinate, dilated along the axes where e is 0.
inline bool piecesTouch(const FaceLayers& p, const FaceLayers& q, const BlockIndex& e) {
  const int a = e.x() != 0 ? 0 : (e.y() != 0 ? 1 : 2);
  const int u = a == 0 ? 1 : 0;
  const int w = a == 2 ? 1 : 2;
  uint64_t lp = p.layer[2 * a + (e[a] > 0 ? 0 : 1)];
  const uint64_t lq = q.layer[2 * a + (e[a] > 0 ? 1 : 0)];
  if (lp == 0 || lq == 0) return false;
  if (e[u] > 0) {
    lp = (lp >> 56) & 0xFF;  // p's row u = 7 next to q's row u = 0
  } else if (e[u] < 0) {
    lp = (lp & 0xFF) << 56;
  } else {
    lp = dilateHigh(lp);
  }
  if (e[w] > 0) {
    lp = (lp & kHighBitOfEachByte) >> 7;
  } else if (e[w] < 0) {
    lp = (lp & kLowBitOfEachByte) << 7;
  } else {
    lp = dilateLow(lp);
  }
  return (lp & lq) != 0;
}

}  // namespace cenote::mapping::detail
