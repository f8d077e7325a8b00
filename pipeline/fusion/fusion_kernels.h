// fusion_kernels.h: the per-row SIMD kernels of depth_fusion.cpp and back_projection.cpp
// (Highway, one build per instruction set, chosen at run time). Internal to pipeline/fusion; the rules they implement are
// documented in depth_fusion.h, and the plain scalar form lives in depth_fusion.cpp (used for
// images narrower than one vector) and in tests/support/fusion_reference.cpp.
// Units: metres, pixels. Threads: pure functions of their arguments; each call writes only its
// own output row.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "pipeline/fusion/fusion_config.h"

namespace cenote::pipeline::detail {

inline constexpr int kMaxFusionViews = FusionConfig::kMaxViews;

// Maps pixel (x, y) of one view with depth Z to another: h = Z * (A [x y 1]^T) + k, pixel
// (h0 / h2, h1 / h2), depth h2 (K's last row is 0 0 1). A = K_to R_to_from K_from^-1, k = K_to t_to_from.
struct Projector {
  float a[9];
  float k[3];
};

// Rule 0 and eps(Z) of depth_fusion.h, in float.
struct FusionLimits {
  float max_depth_m;     // finite
  float min_confidence;  // > 0
  bool relative_eps;
  float eps;
  float min_fused_confidence;
};

// Everything the per-pixel fusion needs, resolved once per call.
struct FusionRowInput {
  int num_views = 0, ref = 0, width = 0, height = 0;
  std::array<const float*, kMaxFusionViews> depth{}, conf{};   // original maps, row 0
  std::array<size_t, kMaxFusionViews> step{};                  // their row step, in floats
  std::array<const float*, kMaxFusionViews> rendered_depth{};  // rendered maps (width-contiguous rows); ref: unused
  std::array<const float*, kMaxFusionViews> rendered_conf{};
  std::array<Projector, kMaxFusionViews> to_view{};  // reference pixel -> view l; ref: unused
  FusionLimits limits{};
};

// Projects row y of a source view into the target image: for each x, out_index[x] = target pixel
// index (row * target_width + column) or -1 when the pixel is invalid or its point is dropped, and
// out_depth[x] = its depth in the target camera (left unwritten where out_index[x] is -1).
// @return the largest out_index[x] (-1 when every pixel is dropped).
int32_t projectRow(const Projector& P, const FusionLimits& limits, const float* depth, const float* conf, int y, int width,
                   int target_width, int target_height, int32_t* out_index, float* out_depth);

// Steps 2-4 of depth_fusion.h for row y of the reference view; width >= fusionLanes().
void fuseRow(const FusionRowInput& in, int y, float* out_depth, float* out_conf);

// Vector width in floats of the instruction set chosen at run time.
int fusionLanes();

// Whether a depth becomes a point: 0 < depth < inf (NaN does not).
inline bool hasPoint(float depth_m) { return (depth_m > 0.0f) & (depth_m < std::numeric_limits<float>::infinity()); }

// The number of pixels of the row `depth` with hasPoint().
size_t countPoints(const float* depth, int width);

// The world ray of pixel (x, y) is row_ray + x * step (per component, in that order of float
// operations), its point z * ray + t.
struct RowRays {
  float row_ray[3];
  float step[3];
  float t[3];
};

// Writes one point (x, y, z floats) per pixel of row `depth` with 0 < depth < inf, in column
// order, to `xyz`, and its colour (R, G, B from the BGR row `bgr`) to `rgb` when bgr is not null.
// Every lane computes z * (row_ray + x * step) + t with separate multiplies and adds (the kernels'
// file is compiled without contraction into fused multiply-adds), so every instruction set, and
// the scalar tail, give the bits of the plain float expression.
// `capacity`: points that xyz and rgb have room for (at least the row's); nothing is written past them.
// @return the number of points written.
size_t backProjectRow(const RowRays& rays, const float* depth, const uint8_t* bgr, int width, float* xyz, uint8_t* rgb,
                      size_t capacity);

}  // namespace cenote::pipeline::detail
