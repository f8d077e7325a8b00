// matcher_kernels.h: the per-pixel image work of the stereo matcher around the SGM engine (the SAD
// prefilter's clamp, the 2x2 halving of the coarse level, depth from disparity), one row at a
// time in SIMD (Highway, one build per instruction set, chosen at run time). Internal to
// pipeline/stereo: the rules are those of stereo_matcher.h (prefilterForSad, halveImage,
// disparityToDepth), which these rows implement exactly, lane by lane, with a scalar tail of the
// same arithmetic. Threads: pure functions of their arguments.
#pragma once

#include <cstdint>

namespace cenote::pipeline::detail {

// out[x] = clamp(derivative[x], -cap, cap) + cap for x < width (0 < cap <= 127).
void clampDerivativeRow(const int16_t* derivative, int width, int cap, uint8_t* out);

// out[x] = (top[2x] + top[2x + 1] + bottom[2x] + bottom[2x + 1] + 2) / 4 for x < half_width; the
// columns past in_width - 1 repeat the last one.
void halveRow(const uint8_t* top, const uint8_t* bottom, int in_width, int half_width, uint8_t* out);

// z[x] = fb / d[x] where d[x] is finite and positive, else +inf, for x < width.
void depthFromDisparityRow(const float* d, int width, float fb, float* z);

}  // namespace cenote::pipeline::detail
