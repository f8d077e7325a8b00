// point_voxels.cpp: Highway implementation of point_voxels.h, compiled once per instruction set.
//
// Why the product gives the division's voxel. toVoxel floors q_div = fl(p / s) (fl: IEEE double
// rounding to nearest, relative error at most u = 2^-53). Here q = fl(p * r) with r = fl(1 / s).
// With Q = p / s exactly: q_div = Q (1 + d1), q = Q (1 + d2)(1 + d3), |d_i| <= u, so
//   |q - q_div| <= |Q| (3u + u^2) <= |q| (3u + u^2) / (1 - u)^2 < |q| 4u,
// which is below 2^-30 wherever |q| < 2^21 (s within 2^+-1000, so r and q are normal numbers: a
// q of magnitude below 2^-28 fails the fraction test below anyway). Let k = floor(q) and
// t = q - k, computed exactly (Sterbenz's lemma where |q| >= 1, t = q where 0 <= q < 1) or, for
// -1 < q < 0, rounded monotonically. A lane whose computed t lies in [2^-28, 1 - 2^-28] has its
// exact t in (2^-29, 1 - 2^-29), so k < q - 2^-30 < q_div < q + 2^-30 < k + 1: floor(q_div) = k,
// toVoxel's voxel. Every other lane (q within 2^-28 of an integer, |q| >= 2^21, NaN, infinity)
// takes toVoxel itself: the vector of 8 lanes (or fewer) holding it is redone in scalar. Integer
// metres at 0.1 m are such lanes: 3 / 0.1 is 29.999999999999996 but 3 * fl(1 / 0.1) is 30.
// Compiled with -ffp-contract=off (mapping/CMakeLists.txt): Mul and Sub each round once.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "mapping/integration/point_voxels.cpp"
#include <hwy/foreach_target.h>  // must precede highway.h
#include <hwy/highway.h>

#include "mapping/integration/point_voxels.h"
#include "mapping/integration/voxel_ray.h"

// Once, not per instruction set (foreach_target.h includes this file again for each).
#ifndef CENOTE_MAPPING_POINT_VOXELS_EXACT
#define CENOTE_MAPPING_POINT_VOXELS_EXACT
namespace cenote::mapping::detail {

// toVoxel, one point after another: the tail, and lanes the product cannot decide.
inline void pointVoxelsExact(const Eigen::Vector3f* points, size_t n, double s, VoxelIndex* out) {
  for (size_t i = 0; i < n; ++i) out[i] = toVoxel(points[i].cast<double>(), s);
}

}  // namespace cenote::mapping::detail
#endif

HWY_BEFORE_NAMESPACE();
namespace cenote::mapping::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using DD = hn::ScalableTag<double>;
using DF = hn::Rebind<float, DD>;  // as many floats as doubles
using DI = hn::Rebind<int32_t, DD>;
using VD = hn::Vec<DD>;

constexpr double kEdge = 0x1p-28;        // a fraction this close to an integer goes to toVoxel
constexpr double kMaxQuotient = 0x1p21;  // beyond it, the error bound above does not hold

// floor(q) of one axis, and whether the product decided it (see the top of the file).
HWY_INLINE VD floorDecided(DD dd, VD q, hn::Mask<DD>& decided) {
  const VD k = hn::Floor(q);
  const VD t = hn::Sub(q, k);
  decided = hn::And(decided, hn::And(hn::And(hn::Ge(t, hn::Set(dd, kEdge)), hn::Le(t, hn::Set(dd, 1.0 - kEdge))),
                                     hn::Lt(hn::Abs(q), hn::Set(dd, kMaxQuotient))));
  return k;
}

void PointVoxelsImpl(const Eigen::Vector3f* points, size_t n, double s, VoxelIndex* out) {
  const DD dd;
  const DF df;
  const DI di;
  const size_t lanes = hn::Lanes(dd);
  const VD r = hn::Set(dd, 1.0 / s);
  size_t i = 0;
  for (; i + lanes <= n; i += lanes) {
    hn::Vec<DF> x, y, z;
    hn::LoadInterleaved3(df, points[i].data(), x, y, z);
    hn::Mask<DD> decided = hn::FirstN(dd, lanes);
    const VD kx = floorDecided(dd, hn::Mul(hn::PromoteTo(dd, x), r), decided);
    const VD ky = floorDecided(dd, hn::Mul(hn::PromoteTo(dd, y), r), decided);
    const VD kz = floorDecided(dd, hn::Mul(hn::PromoteTo(dd, z), r), decided);
    hn::StoreInterleaved3(hn::DemoteTo(di, kx), hn::DemoteTo(di, ky), hn::DemoteTo(di, kz), di, out[i].data());
    if (HWY_UNLIKELY(!hn::AllTrue(dd, decided))) pointVoxelsExact(points + i, lanes, s, out + i);
  }
  pointVoxelsExact(points + i, n - i, s, out + i);
}

}  // namespace HWY_NAMESPACE
}  // namespace cenote::mapping::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace cenote::mapping {
namespace detail {
HWY_EXPORT(PointVoxelsImpl);
void pointVoxelsSimd(const Eigen::Vector3f* points, size_t n, double s, VoxelIndex* out) {
  HWY_DYNAMIC_DISPATCH(PointVoxelsImpl)(points, n, s, out);
}
}  // namespace detail

void pointVoxels(const Eigen::Vector3f* points, size_t n, double voxel_size_m, VoxelIndex* out) {
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float) && sizeof(VoxelIndex) == 3 * sizeof(int32_t),
                "points and voxels are read and written as packed triples");
  if (voxel_size_m > 0x1p-1000 && voxel_size_m < 0x1p1000) {
    detail::pointVoxelsSimd(points, n, voxel_size_m, out);
  } else {
    detail::pointVoxelsExact(points, n, voxel_size_m, out);
  }
}

}  // namespace cenote::mapping
#endif
