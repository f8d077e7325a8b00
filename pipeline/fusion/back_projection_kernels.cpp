// back_projection_kernels.cpp: Highway implementation of back_projection_kernels.h, compiled once
// per instruction set with -ffp-contract=off (pipeline/CMakeLists.txt): a multiply followed by an
// add must stay two roundings, as in the scalar expression.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "pipeline/fusion/back_projection_kernels.cpp"
#include <hwy/foreach_target.h>  // must precede highway.h
#include <hwy/highway.h>

#include <limits>

#include "pipeline/fusion/back_projection_kernels.h"

HWY_BEFORE_NAMESPACE();
namespace cenote::pipeline::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using DF = hn::ScalableTag<float>;

bool hasPoint(float depth_m) { return depth_m > 0.0f && depth_m < std::numeric_limits<float>::infinity(); }

void writeColour(const uint8_t* bgr, int x, uint8_t* rgb) {
  rgb[0] = bgr[3 * x + 2];
  rgb[1] = bgr[3 * x + 1];
  rgb[2] = bgr[3 * x];
}

size_t BackProjectRowImpl(const RowRays& r, const float* depth, const uint8_t* bgr, int width, float* xyz, uint8_t* rgb) {
  const DF df;
  const int lanes = static_cast<int>(hn::Lanes(df));
  const hn::Vec<DF> zero = hn::Zero(df), inf = hn::Set(df, std::numeric_limits<float>::infinity());
  HWY_ALIGN float world[3][hn::MaxLanes(df)];
  size_t count = 0;
  int x = 0;
  for (; x + lanes <= width; x += lanes) {
    const hn::Vec<DF> z = hn::LoadU(df, depth + x);
    if (hn::AllFalse(df, hn::And(hn::Gt(z, zero), hn::Lt(z, inf)))) continue;  // a hole, or rejected pixels
    const hn::Vec<DF> xf = hn::Iota(df, static_cast<float>(x));
    for (int c = 0; c < 3; ++c) {
      const hn::Vec<DF> ray = hn::Add(hn::Set(df, r.row_ray[c]), hn::Mul(xf, hn::Set(df, r.step[c])));
      hn::Store(hn::Add(hn::Mul(z, ray), hn::Set(df, r.t[c])), df, world[c]);
    }
    for (int k = 0; k < lanes; ++k) {
      if (!hasPoint(depth[x + k])) continue;
      float* p = xyz + 3 * count;
      p[0] = world[0][k];
      p[1] = world[1][k];
      p[2] = world[2][k];
      if (bgr) writeColour(bgr, x + k, rgb + 3 * count);
      ++count;
    }
  }
  for (; x < width; ++x) {  // the last pixels, fewer than a vector: the lanes' arithmetic in scalar
    if (!hasPoint(depth[x])) continue;
    const float xf = static_cast<float>(x);
    for (int c = 0; c < 3; ++c) xyz[3 * count + c] = depth[x] * (r.row_ray[c] + xf * r.step[c]) + r.t[c];
    if (bgr) writeColour(bgr, x, rgb + 3 * count);
    ++count;
  }
  return count;
}

}  // namespace HWY_NAMESPACE
}  // namespace cenote::pipeline::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace cenote::pipeline::detail {

HWY_EXPORT(BackProjectRowImpl);

size_t backProjectRow(const RowRays& rays, const float* depth, const uint8_t* bgr, int width, float* xyz, uint8_t* rgb) {
  return HWY_DYNAMIC_DISPATCH(BackProjectRowImpl)(rays, depth, bgr, width, xyz, rgb);
}

}  // namespace cenote::pipeline::detail
#endif
