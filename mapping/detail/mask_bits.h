// mask_bits.h: the voxels a block's 512-bit mask marks (BlockView::known, a colour mask), one by
// one, for code that walks them without OpenVDB.
// Units: in-block offsets (offsetInBlock: word w holds x = w, bit y * 8 + z). Threads: pure functions.
#pragma once

#include <array>
#include <cstdint>

namespace cenote::mapping::detail {

// visit(offset) for each set bit of `mask`, in increasing offset.
template <typename Visit>
inline void forEachSetBit(const std::array<uint64_t, 8>& mask, Visit&& visit) {
  for (int w = 0; w < 8; ++w) {
    for (uint64_t bits = mask[w]; bits != 0; bits &= bits - 1) visit(w * 64 + __builtin_ctzll(bits));
  }
}

}  // namespace cenote::mapping::detail
