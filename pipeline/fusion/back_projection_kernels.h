// back_projection_kernels.h: the per-row SIMD kernel of back_projection.cpp (Highway, one build
// per instruction set, chosen at run time). Internal to pipeline/fusion.
// Units: metres, pixels. Threads: a pure function of its arguments; writes only the points it makes.
#pragma once

#include <cstddef>
#include <cstdint>

namespace cenote::pipeline::detail {

// The world ray of pixel (x, y) is row_ray + x * step (per component, in that order of float
// operations), its point z * ray + t.
struct RowRays {
  float row_ray[3];
  float step[3];
  float t[3];
};

// Writes one point (x, y, z floats) per pixel of row `depth` with 0 < depth < inf, in column
// order, to `xyz`, and its colour (R, G, B from the BGR row `bgr`) to `rgb` when bgr is not null.
// Every lane computes z * (row_ray + x * step) + t with separate multiplies and adds (the file is
// compiled without contraction into fused multiply-adds), so every instruction set, and the
// scalar tail, give the bits of the plain float expression.
// @return the number of points written.
size_t backProjectRow(const RowRays& rays, const float* depth, const uint8_t* bgr, int width, float* xyz, uint8_t* rgb);

}  // namespace cenote::pipeline::detail
