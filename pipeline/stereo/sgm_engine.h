// sgm_engine.h: the hot loops of StereoMatcher (internal; use stereo_matcher.h).
//
// One horizontal strip of the rectified pair is matched in a single top-down pass (4 paths: left,
// up, up-left, up-right, as rSGM) or in two passes (8 paths; the first pass's path sums are kept in
// a per-strip volume). The full cost volume is never stored: the matching cost of one row is built
// from running box sums, aggregated along the paths, and the winner, second minimum and parabola
// are taken on the fly. Costs, paths and the winner search are uint16 SIMD (a census band's paths
// in bytes where they fit, bandFitsBytes()); disparity, sub-pixel
// offset and PKRN are float SIMD over batches of pixels (Highway, dispatched at run time to the
// best instruction set of the machine). The result depends only on the input and the strip
// boundaries, never on the thread count.
// With SgmImages::band_start each pixel searches only kBandDisparities disparities (coarse to
// fine; band_placement.h places the bands from a coarse match): one vector of path costs per pixel, and
// SAD window sums only over the bands of the pixels whose window holds a column.
//
// Threads: matchStrip() may run concurrently for different strips, each with its own workspace.
#pragma once

#include <hwy/aligned_allocator.h>

#include <cstddef>
#include <cstdint>

#include "pipeline/stereo/stereo_config.h"

namespace cenote::pipeline::detail {

struct SgmParams {
  int width = 0;
  int height = 0;
  int num_disparities = 0;  // D, a multiple of 16
  int min_disparity = 0;
  bool census = false;  // false: SAD over window x window
  int window = 3;
  int sad_shift = 0;
  int max_cost = 0;
  int p1 = 0;
  int p2 = 0;
  bool adaptive_p2 = false;
  float p2_gradient_scale = 8.0f;
  bool eight_paths = false;
  bool subpixel = true;
  bool pkrn_exclude_neighbours = true;
  bool lr_check = false;
  bool invalidate_truncated = false;
  int lr_max_diff = 1;
  float min_confidence = 0.0f;
};

// The engine's parameters of a matcher configuration (penalties and cost range resolved; strips
// and the search mode are the matcher's).
SgmParams paramsOf(const StereoConfig& config);

// The path cost of a disparity a path pixel does not hold (lanes past D; in the band, outside the
// pixel's band): it loses against every real predecessor even after + P1. Path costs are at most
// max_cost + P2; in the band the minimum of a predecessor may be up to max_cost + P2 as well (a
// pixel's band may miss its predecessor's entirely), so the sentinel must also lose against
// min + P2 there.
inline uint16_t pathSentinel(const SgmParams& p, bool band) {
  return static_cast<uint16_t>(p.max_cost + (band ? 2 : 1) * p.p2 + p.p1);
}

// Whether the census band runs in byte lanes (sgm_band_bytes-inl.h): the largest value its
// recurrence forms (a sentinel plus P1) and the sum of four path costs (each at most max_cost + P2)
// fit in a byte. Census 5x5 and 3x3 at their default penalties do; the output is the same either way.
inline bool bandFitsBytes(const SgmParams& p) {
  return p.census && pathSentinel(p, true) + p.p1 <= 255 && 4 * (p.max_cost + p.p2) <= 255;
}

// Images with a border of `kImageBorder` replicated pixels on every side; pointers address pixel
// (0, 0) inside the border. Census images hold one 32-bit descriptor per pixel (no border).
inline constexpr int kImageBorder = 4;
struct SgmImages {
  const uint8_t* guide = nullptr;  // grey left image: intensity steps adapt P2
  const uint8_t* left = nullptr;   // what SAD compares (grey or prefiltered)
  const uint8_t* right = nullptr;
  std::ptrdiff_t image_stride = 0;  // bytes per row of guide/left/right
  const uint32_t* census_left = nullptr;
  const uint32_t* census_right = nullptr;
  std::ptrdiff_t census_stride = 0;  // elements per row
  // Coarse-to-fine band (null: every pixel searches all disparities): pixel (x, y) searches
  // disparity indices [band_start[y * band_stride + x], + kBandDisparities), inside [0, D).
  const int16_t* band_start = nullptr;
  std::ptrdiff_t band_stride = 0;  // elements per row
};

struct SgmOutput {
  float* disparity = nullptr;   // +inf where invalid
  float* confidence = nullptr;  // PKRN ratio, 0 where invalid
  std::ptrdiff_t stride = 0;    // elements per row, for both
};

// Buffers of one strip, kept between frames so that a frame allocates nothing.
struct SgmWorkspace {
  hwy::AlignedFreeUniquePtr<uint16_t[]> buffer;
  std::size_t buffer_elements = 0;
  hwy::AlignedFreeUniquePtr<uint16_t[]> volume;  // 8 paths: first-pass sums of the strip's rows
  std::size_t volume_elements = 0;
};

// Matches rows [row_begin, row_end) of the output, starting `overlap` rows earlier (and, with 8
// paths, ending `overlap` rows later) so that the vertical paths are warmed up at the strip border.
void matchStrip(const SgmParams& params, const SgmImages& images, int row_begin, int row_end, int overlap,
                SgmWorkspace& workspace, const SgmOutput& output);

// Census transform of one image (bordered as in SgmImages): bit set where neighbour < centre,
// over a window x window neighbourhood without the centre (window 3 or 5).
// Rows [row_begin, row_end) only, so that callers can split the image between threads.
void censusTransform(const uint8_t* image, std::ptrdiff_t image_stride, int width, int row_begin, int row_end, int window,
                     uint32_t* out, std::ptrdiff_t out_stride);

// Number of uint16 lanes of the dispatched instruction set (the disparity padding unit).
int sgmVectorLanes();

}  // namespace cenote::pipeline::detail
