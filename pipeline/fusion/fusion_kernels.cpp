// fusion_kernels.cpp: Highway implementation of fusion_kernels.h, compiled once per instruction set.
// Every lane is one pixel and sees the same operations whatever the lane count of neighbours, so a
// pixel's result does not depend on how rows are shared between threads. The last vector of a row
// of the projection and fusion kernels is shifted back to end at the last pixel (overlapping the
// previous one) instead of a scalar tail; the back-projection, which writes only some pixels, ends
// with a scalar tail of the same arithmetic.
// Compiled with -ffp-contract=off (pipeline/CMakeLists.txt): a product and a sum are fused only
// where the code says MulAdd or NegMulAdd, so the bits do not depend on the compiler's choices.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "pipeline/fusion/fusion_kernels.cpp"
#include <hwy/foreach_target.h>  // must precede highway.h
#include <hwy/highway.h>

#include <algorithm>
#include <limits>

#include "pipeline/fusion/fusion_kernels.h"

HWY_BEFORE_NAMESPACE();
namespace cenote::pipeline::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using DF = hn::ScalableTag<float>;
using DI = hn::RebindToSigned<DF>;
using VF = hn::Vec<DF>;
using VI = hn::Vec<DI>;
using MF = hn::Mask<DF>;

// Rule 0: 0 < Z <= max_depth and C >= min_confidence (NaN fails every comparison).
HWY_INLINE MF validPixels(DF df, VF z, VF c, const FusionLimits& l) {
  return hn::And(hn::And(hn::Gt(z, hn::Zero(df)), hn::Le(z, hn::Set(df, l.max_depth_m))),
                 hn::Ge(c, hn::Set(df, l.min_confidence)));
}

HWY_INLINE VF epsAt(DF df, VF z, const FusionLimits& l) {
  return l.relative_eps ? hn::Mul(z, hn::Set(df, l.eps)) : hn::Set(df, l.eps);
}

// a[i] y + a[i + 1], the row's part of a ray: one rounding where the target has fused
// multiply-add, two elsewhere, as every MulAdd here (the file is compiled with -ffp-contract=off,
// so no other product and sum are fused behind the code's back).
HWY_INLINE VF rowTerm(DF df, const float* a, int i, float y) {
  return hn::MulAdd(hn::Set(df, a[i]), hn::Set(df, y), hn::Set(df, a[i + 1]));
}

// z - eps(depth): with a relative eps, one multiply-add.
HWY_INLINE VF belowByEps(DF df, VF z, VF depth, const FusionLimits& l) {
  return l.relative_eps ? hn::NegMulAdd(depth, hn::Set(df, l.eps), z) : hn::Sub(z, hn::Set(df, l.eps));
}

// Projection of depth z along ray r = A [x y 1]^T: nearest pixel index (0 where dropped), depth h2,
// and the mask of lanes that land inside the image in front of the camera.
struct Projected {
  VI index;
  VF depth;
  MF inside;
};

HWY_INLINE Projected project(DF df, DI di, VF z, VF r0, VF r1, VF r2, const Projector& P, int width, int height,
                             size_t step) {
  const VF hz = hn::MulAdd(z, r2, hn::Set(df, P.k[2]));
  const VF inv = hn::Div(hn::Set(df, 1.0f), hz);
  const VF u = hn::Mul(hn::MulAdd(z, r0, hn::Set(df, P.k[0])), inv);
  const VF v = hn::Mul(hn::MulAdd(z, r1, hn::Set(df, P.k[1])), inv);
  const VF half = hn::Set(df, 0.5f);
  MF inside = hn::And(hn::Gt(hz, hn::Zero(df)),
                      hn::And(hn::And(hn::Ge(u, hn::Neg(half)), hn::Lt(u, hn::Set(df, static_cast<float>(width)))),
                              hn::And(hn::Ge(v, hn::Neg(half)), hn::Lt(v, hn::Set(df, static_cast<float>(height))))));
  // u + 0.5 >= 0 in the lanes that count, so truncation is floor(u + 0.5); other lanes are masked.
  const VI iu = hn::ConvertTo(di, hn::IfThenElseZero(inside, hn::Add(u, half)));
  const VI iv = hn::ConvertTo(di, hn::IfThenElseZero(inside, hn::Add(v, half)));
  const auto inside_i = hn::And(hn::RebindMask(di, inside),
                                hn::And(hn::Lt(iu, hn::Set(di, width)), hn::Lt(iv, hn::Set(di, height))));
  inside = hn::RebindMask(df, inside_i);
  const VI index = hn::IfThenElseZero(inside_i, hn::Add(hn::Mul(iv, hn::Set(di, static_cast<int>(step))), iu));
  return {index, hz, inside};
}

int32_t ProjectRowImpl(const Projector& P, const FusionLimits& limits, const float* depth, const float* conf, int y,
                       int width, int target_width, int target_height, int32_t* out_index, float* out_depth) {
  const DF df;
  const DI di;
  const int lanes = static_cast<int>(hn::Lanes(df));
  const float yf = static_cast<float>(y);
  const VF b0 = rowTerm(df, P.a, 1, yf), b1 = rowTerm(df, P.a, 4, yf), b2 = rowTerm(df, P.a, 7, yf);
  const VF a0 = hn::Set(df, P.a[0]), a3 = hn::Set(df, P.a[3]), a6 = hn::Set(df, P.a[6]);
  VI max_index = hn::Set(di, -1);
  for (int start = 0; start < width; start += lanes) {
    const int x = std::min(start, width - lanes);
    const VF xs = hn::Iota(df, static_cast<float>(x));
    const VF z = hn::LoadU(df, depth + x), c = hn::LoadU(df, conf + x);
    const MF valid = validPixels(df, z, c, limits);
    if (hn::AllFalse(df, valid)) {  // a hole or the far side of the scene: no point to project
      hn::StoreU(hn::Set(di, -1), di, out_index + x);
      continue;
    }
    const VF z_safe = hn::IfThenElse(valid, z, hn::Set(df, 1.0f));
    const Projected p = project(df, di, z_safe, hn::MulAdd(xs, a0, b0), hn::MulAdd(xs, a3, b1), hn::MulAdd(xs, a6, b2), P,
                                target_width, target_height, static_cast<size_t>(target_width));
    const auto keep = hn::RebindMask(di, hn::And(valid, p.inside));
    const VI index = hn::IfThenElse(keep, p.index, hn::Set(di, -1));
    max_index = hn::Max(max_index, index);
    hn::StoreU(index, di, out_index + x);
    hn::StoreU(p.depth, df, out_depth + x);
  }
  return hn::GetLane(hn::MaxOfLanes(di, max_index));
}

// Steps 2-4 for one row. kViews > 0 is N_f known when compiling (3 and 5: the loops over views
// unroll and the candidates stay in registers); 0 takes in.num_views. Both do the same operations
// in the same order on every lane, so their results are the same bits.
template <int kViews>
HWY_INLINE void fuseRowOf(const FusionRowInput& in, int y, float* out_depth, float* out_conf) {
  const DF df;
  const DI di;
  const int lanes = static_cast<int>(hn::Lanes(df));
  const int n = kViews > 0 ? kViews : in.num_views, r = kViews > 0 ? (kViews - 1) / 2 : in.ref;
  const FusionLimits& lim = in.limits;
  const float yf = static_cast<float>(y);
  const VF inf = hn::Set(df, std::numeric_limits<float>::infinity());
  const VF zero = hn::Zero(df);
  const size_t row = static_cast<size_t>(y) * in.width;
  const float* ref_depth = in.depth[r] + y * in.step[r];
  const float* ref_conf = in.conf[r] + y * in.step[r];

  for (int start = 0; start < in.width; start += lanes) {
    const int x = std::min(start, in.width - lanes);
    const VF xs = hn::Iota(df, static_cast<float>(x));
    // Step 2: candidates, +inf / 0 where a view has none.
    constexpr int kSlots = kViews > 0 ? kViews : kMaxFusionViews;
    VF z[kSlots], c[kSlots];
    MF has[kSlots];
    MF any = hn::FirstN(df, 0);
    for (int v = 0; v < n; ++v) {
      if (v == r) {
        const VF zr = hn::LoadU(df, ref_depth + x), cr = hn::LoadU(df, ref_conf + x);
        has[v] = validPixels(df, zr, cr, lim);
        z[v] = hn::IfThenElse(has[v], zr, inf);
        c[v] = hn::IfThenElseZero(has[v], cr);
      } else {
        z[v] = hn::LoadU(df, in.rendered_depth[v] + row + x);
        c[v] = hn::LoadU(df, in.rendered_conf[v] + row + x);
        has[v] = hn::Lt(z[v], inf);
      }
      any = hn::Or(any, has[v]);
    }
    // No candidate in any lane: every pixel is rejected (what the steps below would give).
    if (hn::AllFalse(df, any)) {
      hn::StoreU(inf, df, out_depth + x);
      hn::StoreU(zero, df, out_conf + x);
      continue;
    }
    // Rays of the reference pixels in every other view.
    VF ray[kSlots][3];
    for (int l = 0; l < n; ++l) {
      if (l == r) continue;
      const float* a = in.to_view[l].a;
      ray[l][0] = hn::MulAdd(xs, hn::Set(df, a[0]), rowTerm(df, a, 1, yf));
      ray[l][1] = hn::MulAdd(xs, hn::Set(df, a[3]), rowTerm(df, a, 4, yf));
      ray[l][2] = hn::MulAdd(xs, hn::Set(df, a[6]), rowTerm(df, a, 7, yf));
    }

    // Steps 3 and 4: every candidate in full; the first strictly better one wins.
    VF best_conf = hn::Set(df, -std::numeric_limits<float>::infinity());
    VF best_weighted = zero, best_support = hn::Set(df, 1.0f);  // depth = weighted / support, once
    for (int j = 0; j < n; ++j) {
      // No lane has this candidate: none of them would take it.
      if (hn::AllFalse(df, has[j])) continue;
      const VF zj = hn::IfThenElse(has[j], z[j], hn::Set(df, 1.0f));  // finite in unused lanes
      const VF e = epsAt(df, zj, lim);
      const VF minus_e = hn::Neg(e);
      VF support = zero, weighted = zero, conflict = zero;
      for (int i = 0; i < n; ++i) {
        const VF diff = hn::Sub(z[i], zj);
        const MF supports = hn::Lt(hn::Abs(diff), e);  // false for a missing i (diff = +inf)
        support = hn::Add(support, hn::IfThenElseZero(supports, c[i]));
        weighted = hn::Add(weighted, hn::IfThenElseZero(supports, hn::Mul(c[i], z[i])));
        conflict = hn::Add(conflict, hn::IfThenElseZero(hn::Lt(diff, minus_e), c[i]));  // occlusion
      }
      for (int l = 0; l < n; ++l) {
        if (l == j) continue;
        if (l == r) {
          const MF violates = hn::And(has[r], hn::Lt(zj, hn::Sub(z[r], e)));
          conflict = hn::Add(conflict, hn::IfThenElseZero(violates, c[r]));
          continue;
        }
        const Projected p = project(df, di, zj, ray[l][0], ray[l][1], ray[l][2], in.to_view[l], in.width, in.height,
                                    in.step[l]);
        const VF zl = hn::GatherIndex(df, in.depth[l], p.index);
        const VF cl = hn::GatherIndex(df, in.conf[l], p.index);
        const MF violates = hn::And(hn::And(p.inside, validPixels(df, zl, cl, lim)),
                                    hn::Lt(p.depth, belowByEps(df, zl, p.depth, lim)));
        conflict = hn::Add(conflict, hn::IfThenElseZero(violates, cl));
      }
      const VF fused = hn::Sub(support, conflict);
      const MF better = hn::And(has[j], hn::Gt(fused, best_conf));
      best_conf = hn::IfThenElse(better, fused, best_conf);
      best_weighted = hn::IfThenElse(better, weighted, best_weighted);
      best_support = hn::IfThenElse(better, support, best_support);
    }
    const MF keep = hn::Ge(best_conf, hn::Set(df, lim.min_fused_confidence));
    hn::StoreU(hn::IfThenElse(keep, hn::Div(best_weighted, best_support), inf), df, out_depth + x);
    hn::StoreU(hn::IfThenElseZero(keep, best_conf), df, out_conf + x);
  }
}

void FuseRowImpl(const FusionRowInput& in, int y, float* out_depth, float* out_conf) {
  switch (in.num_views) {
    case 3: return fuseRowOf<3>(in, y, out_depth, out_conf);
    case 5: return fuseRowOf<5>(in, y, out_depth, out_conf);
    default: return fuseRowOf<0>(in, y, out_depth, out_conf);
  }
}

// Back-projection of one row (back_projection.cpp): separate multiplies and adds, the plain
// float expression's bits on every instruction set.

void writeColour(const uint8_t* bgr, int x, uint8_t* rgb) {
  rgb[0] = bgr[3 * x + 2];
  rgb[1] = bgr[3 * x + 1];
  rgb[2] = bgr[3 * x];
}

// AVX-512 compresses a vector in one instruction; elsewhere Highway emulates it at a cost that
// exceeds the per-lane loop (callgrind, AVX2: three times the instructions).
constexpr bool kNativeCompress = HWY_TARGET <= HWY_AVX3;

size_t BackProjectRowImpl(const RowRays& r, const float* depth, const uint8_t* bgr, int width, float* xyz, uint8_t* rgb,
                          size_t capacity) {
  const DF df;
  const DI di;
  const int lanes = static_cast<int>(hn::Lanes(df));
  const hn::Vec<DF> zero = hn::Zero(df), inf = hn::Set(df, std::numeric_limits<float>::infinity());
  HWY_ALIGN float packed[3 * hn::MaxLanes(df)];
  HWY_ALIGN int32_t columns[hn::MaxLanes(di)];
  size_t count = 0;
  int x = 0;
  for (; x + lanes <= width; x += lanes) {
    const hn::Vec<DF> z = hn::LoadU(df, depth + x);
    const MF has = hn::And(hn::Gt(z, zero), hn::Lt(z, inf));
    if (hn::AllFalse(df, has)) continue;  // a hole, or rejected pixels
    const hn::Vec<DF> xf = hn::Iota(df, static_cast<float>(x));
    hn::Vec<DF> world[3];
    for (int c = 0; c < 3; ++c) {
      const hn::Vec<DF> ray = hn::Add(hn::Set(df, r.row_ray[c]), hn::Mul(xf, hn::Set(df, r.step[c])));
      world[c] = hn::Add(hn::Mul(z, ray), hn::Set(df, r.t[c]));
    }
    if constexpr (kNativeCompress) {
      // The points first, in order. A whole vector of them is stored where it fits (the lanes
      // past n are overwritten by the next points); near the end of the caller's space, through
      // a buffer.
      for (int c = 0; c < 3; ++c) world[c] = hn::Compress(world[c], has);
      const size_t n = hn::CountTrue(df, has);
      float* out = count + lanes <= capacity ? xyz + 3 * count : packed;
      hn::StoreInterleaved3(world[0], world[1], world[2], df, out);
      if (out == packed) std::copy(packed, packed + 3 * n, xyz + 3 * count);
      if (bgr) {
        hn::Store(hn::Compress(hn::Iota(di, x), hn::RebindMask(di, has)), di, columns);
        for (size_t k = 0; k < n; ++k) writeColour(bgr, columns[k], rgb + 3 * (count + k));
      }
      count += n;
    } else {
      for (int c = 0; c < 3; ++c) hn::Store(world[c], df, packed + c * lanes);
      for (int k = 0; k < lanes; ++k) {
        if (!hasPoint(depth[x + k])) continue;
        float* p = xyz + 3 * count;
        p[0] = packed[k];
        p[1] = packed[lanes + k];
        p[2] = packed[2 * lanes + k];
        if (bgr) writeColour(bgr, x + k, rgb + 3 * count);
        ++count;
      }
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

size_t CountPointsImpl(const float* depth, int width) {
  const DF df;
  const int lanes = static_cast<int>(hn::Lanes(df));
  const VF zero = hn::Zero(df), inf = hn::Set(df, std::numeric_limits<float>::infinity());
  size_t count = 0;
  int x = 0;
  for (; x + lanes <= width; x += lanes) {
    const VF z = hn::LoadU(df, depth + x);
    count += hn::CountTrue(df, hn::And(hn::Gt(z, zero), hn::Lt(z, inf)));
  }
  for (; x < width; ++x) count += hasPoint(depth[x]);
  return count;
}

int FusionLanesImpl() { return static_cast<int>(hn::Lanes(DF())); }

}  // namespace HWY_NAMESPACE
}  // namespace cenote::pipeline::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace cenote::pipeline::detail {

HWY_EXPORT(ProjectRowImpl);
HWY_EXPORT(FuseRowImpl);
HWY_EXPORT(FusionLanesImpl);
HWY_EXPORT(BackProjectRowImpl);
HWY_EXPORT(CountPointsImpl);

int32_t projectRow(const Projector& P, const FusionLimits& limits, const float* depth, const float* conf, int y, int width,
                   int target_width, int target_height, int32_t* out_index, float* out_depth) {
  return HWY_DYNAMIC_DISPATCH(ProjectRowImpl)(P, limits, depth, conf, y, width, target_width, target_height, out_index,
                                              out_depth);
}

void fuseRow(const FusionRowInput& in, int y, float* out_depth, float* out_conf) {
  HWY_DYNAMIC_DISPATCH(FuseRowImpl)(in, y, out_depth, out_conf);
}

int fusionLanes() { return HWY_DYNAMIC_DISPATCH(FusionLanesImpl)(); }

size_t backProjectRow(const RowRays& rays, const float* depth, const uint8_t* bgr, int width, float* xyz, uint8_t* rgb,
                      size_t capacity) {
  return HWY_DYNAMIC_DISPATCH(BackProjectRowImpl)(rays, depth, bgr, width, xyz, rgb, capacity);
}

size_t countPoints(const float* depth, int width) { return HWY_DYNAMIC_DISPATCH(CountPointsImpl)(depth, width); }

}  // namespace cenote::pipeline::detail
#endif
