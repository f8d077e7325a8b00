// band_placement.h: where each full-size pixel's band of kBandDisparities disparities lies, from
// the coarse match (SearchMode::kBand; internal to StereoMatcher, and to its scalar reference's tests).
//
// A pixel's 3x3 coarse neighbourhood (coarse pixel (x / s, y / s) and its neighbours, s the coarse
// scale) holds the candidates: a pixel near the edge of its coarse pixel may belong to a
// neighbour's surface.
//   - Where the neighbourhood's coarse disparities fit in the band with kBandMargin to spare, the
//     band covers them all, centred between their extremes.
//   - Elsewhere (a depth edge: the surfaces are further apart than one band) the pixel checks its
//     own full-size match: each distinct coarse disparity v of the neighbourhood scores the least
//     5x5 SAD, on the image the cost compares, over the disparities s v - s / 2 .. s v + s / 2 that
//     have a right pixel (at most x); the best score wins (the smaller v on ties; the smallest v
//     where none has a right pixel). The band then covers as many neighbourhood values as
//     fit beside the winner (the lowest such window on ties). Centring on the pixel's own coarse
//     disparity instead left band search 0.83 points of bad-2 above full search on Motorcycle and
//     1.56 on Aloe, against 0.36 and 0.40 with the check (middlebury_test.cpp). The check runs
//     once per coarse pixel's block of pixels, sharing window rows (docs/PERFORMANCE.md): about
//     1 % of an 800x600x112 frame of Cloth3, and a fifth of the instructions where nearly every coarse
//     pixel is at an edge.
//     In the columns whose output StereoConfig::invalidate_truncated marks invalid (x < min_d + D - 1),
//     where a band only feeds the paths, an edge pixel's band is centred on its own coarse disparity
//     instead: on the 800x600x112 bench they hold most edge pixels.
//   - No finite coarse disparity around: the band starts at 0 (StereoConfig::bandStart).
#pragma once

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "pipeline/stereo/stereo_config.h"

namespace cenote::pipeline::detail {

inline constexpr int kBandMargin = 2;       // full-size pixels kept beyond the neighbourhood's disparities
inline constexpr int kEdgeCheckRadius = 2;  // the edge check's SAD window: 5x5
inline constexpr int kEdgeCheckBorder = 4;  // replicated pixels around EdgeCheckImages, at least

// The full-size image pair that the edge check compares, with a replicated border of
// kEdgeCheckBorder pixels on every side (rows contiguous, as the matcher's bordered images, so
// that a window may read 3 bytes past its row); pointers address pixel (0, 0).
struct EdgeCheckImages {
  const uint8_t* left = nullptr;
  const uint8_t* right = nullptr;
  std::ptrdiff_t stride = 0;
  int width = 0;
  int height = 0;
};

// Scratch of one strip, kept between frames.
struct BandScratch {
  std::vector<int> centres;     // per coarse column of one coarse row: band centre or a marker
  std::vector<int16_t> values;  // per coarse column: the neighbourhood's distinct values (edges)
  std::vector<uint8_t> counts;  // per coarse column: how many of them
  std::vector<int> edges;       // the coarse columns at depth edges
  // Per coarse column of the three coarse rows around one: smallest and largest finite
  // disparity (+-FLT_MAX where none) and how many are finite.
  std::vector<float> column_lo, column_hi;
  std::vector<uint8_t> column_finite;
};

// First disparity index of each pixel's band, rows [y0, y1) of `band_start` (CV_16S, full size),
// from the coarse match's rows [coarse_y0, coarse_y1) (the coarse rows of the strip).
void placeBands(const cv::Mat& coarse_disparity, const StereoConfig& config, const EdgeCheckImages& images, int coarse_y0,
                int coarse_y1, int y0, int y1, BandScratch& scratch, cv::Mat& band_start);

}  // namespace cenote::pipeline::detail
