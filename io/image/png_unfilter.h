// png_unfilter.h: the SIMD kernel of png_decoder.cpp for PNG's Sub filter (specification, section
// 9.2) on 3-byte pixels, the filter of the RGB frames stereo sequences are made of (OpenCV and
// our own encoder write every row with it). Highway, one build per instruction set, chosen at run
// time. Threads: a pure function of its arguments.
#pragma once

#include <cstddef>
#include <cstdint>

namespace cenote::io::detail {

// out[i] = in[i] + out[i - 3] (modulo 256; 0 before the row), for i in [0, length). `out` may be
// `in` itself.
void unfilterSubRgb(const uint8_t* in, uint8_t* out, std::size_t length);

}  // namespace cenote::io::detail
