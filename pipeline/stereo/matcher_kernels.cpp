// matcher_kernels.cpp: Highway implementation of matcher_kernels.h, compiled once per instruction
// set. Every lane is one pixel and computes what the scalar tail does for the pixels past the last
// whole vector: integer arithmetic, and one IEEE division per pixel, so the bits do not depend on
// the instruction set.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "pipeline/stereo/matcher_kernels.cpp"
#include <hwy/foreach_target.h>  // must precede highway.h
#include <hwy/highway.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "pipeline/stereo/matcher_kernels.h"

HWY_BEFORE_NAMESPACE();
namespace cenote::pipeline::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

void ClampDerivativeRowImpl(const int16_t* derivative, int width, int cap, uint8_t* out) {
  const hn::ScalableTag<int16_t> d16;
  const hn::Rebind<uint8_t, decltype(d16)> d8;
  const int N = static_cast<int>(hn::Lanes(d16));
  const auto lo = hn::Set(d16, static_cast<int16_t>(-cap)), hi = hn::Set(d16, static_cast<int16_t>(cap));
  int x = 0;
  for (; x + N <= width; x += N) {
    const auto v = hn::Add(hn::Min(hn::Max(hn::LoadU(d16, derivative + x), lo), hi), hi);  // in [0, 2 cap]
    hn::StoreU(hn::DemoteTo(d8, v), d8, out + x);
  }
  for (; x < width; ++x) out[x] = static_cast<uint8_t>(std::clamp<int>(derivative[x], -cap, cap) + cap);
}

void HalveRowImpl(const uint8_t* top, const uint8_t* bottom, int in_width, int half_width, uint8_t* out) {
  int x = 0;
#if HWY_TARGET != HWY_SCALAR  // one lane cannot hold a pixel's two bytes
  const hn::ScalableTag<uint8_t> d8;
  const hn::Repartition<uint16_t, decltype(d8)> d16;  // one lane per output pixel: bytes 2x, 2x + 1
  const hn::RebindToSigned<decltype(d16)> di16;       // DemoteTo narrows signed lanes
  const hn::Rebind<uint8_t, decltype(d16)> d8_half;
  const int N = static_cast<int>(hn::Lanes(d16));
  const auto low_byte = hn::Set(d16, 0x00FF), two = hn::Set(d16, 2);
  auto pairSums = [&](const uint8_t* row) HWY_ATTR {
    const auto v = hn::BitCast(d16, hn::LoadU(d8, row));
    return hn::Add(hn::And(v, low_byte), hn::ShiftRight<8>(v));
  };
  for (; 2 * (x + N) <= in_width; x += N) {  // every pixel's two columns inside the row
    const int c = 2 * x;
    const auto sum = hn::Add(hn::Add(pairSums(top + c), pairSums(bottom + c)), two);
    hn::StoreU(hn::DemoteTo(d8_half, hn::BitCast(di16, hn::ShiftRight<2>(sum))), d8_half, out + x);
  }
#endif
  const int last_column = in_width - 1;
  for (; x < half_width; ++x) {
    const int x1 = std::min(2 * x + 1, last_column);
    out[x] = static_cast<uint8_t>((top[2 * x] + top[x1] + bottom[2 * x] + bottom[x1] + 2) / 4);
  }
}

void DepthFromDisparityRowImpl(const float* d, int width, float fb, float* z) {
  const hn::ScalableTag<float> df;
  const int N = static_cast<int>(hn::Lanes(df));
  const auto inf = hn::Set(df, std::numeric_limits<float>::infinity()), fb_v = hn::Set(df, fb);
  int x = 0;
  for (; x + N <= width; x += N) {
    const auto v = hn::LoadU(df, d + x);
    // Finite and positive: 0 < d < inf (NaN fails both).
    const auto valid = hn::And(hn::Gt(v, hn::Zero(df)), hn::Lt(v, inf));
    hn::StoreU(hn::IfThenElse(valid, hn::Div(fb_v, v), inf), df, z + x);
  }
  for (; x < width; ++x) z[x] = (std::isfinite(d[x]) && d[x] > 0.0f) ? fb / d[x] : std::numeric_limits<float>::infinity();
}

}  // namespace HWY_NAMESPACE
}  // namespace cenote::pipeline::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace cenote::pipeline::detail {

HWY_EXPORT(ClampDerivativeRowImpl);
HWY_EXPORT(HalveRowImpl);
HWY_EXPORT(DepthFromDisparityRowImpl);

void clampDerivativeRow(const int16_t* derivative, int width, int cap, uint8_t* out) {
  HWY_DYNAMIC_DISPATCH(ClampDerivativeRowImpl)(derivative, width, cap, out);
}

void halveRow(const uint8_t* top, const uint8_t* bottom, int in_width, int half_width, uint8_t* out) {
  HWY_DYNAMIC_DISPATCH(HalveRowImpl)(top, bottom, in_width, half_width, out);
}

void depthFromDisparityRow(const float* d, int width, float fb, float* z) {
  HWY_DYNAMIC_DISPATCH(DepthFromDisparityRowImpl)(d, width, fb, z);
}

}  // namespace cenote::pipeline::detail
#endif
