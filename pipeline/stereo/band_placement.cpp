#include "pipeline/stereo/band_placement.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdlib>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace cenote::pipeline::detail {
namespace {

constexpr int kNoCentre = INT32_MIN;                       // no finite coarse disparity around
constexpr int kEdge = INT32_MIN + 1;                       // a depth edge: the centre is chosen per full-size pixel
constexpr int kNeighbourhood = 9;                          // values of a 3x3 neighbourhood
constexpr int kSpan = kBandDisparities - 2 * kBandMargin;  // full-size disparities a band covers with margins

// Centres of coarse row cy, and for its edge pixels the neighbourhood's distinct values, ascending.
void coarseRowCentres(const cv::Mat& coarse_disparity, int scale, int coarse_y0, int coarse_y1, int cy,
                      BandScratch& scratch) {
  const int width = coarse_disparity.cols;
  scratch.centres.resize(width);
  scratch.values.resize(static_cast<std::size_t>(width) * kNeighbourhood);
  scratch.counts.resize(width);
  const float* rows[3];
  for (int dy = -1; dy <= 1; ++dy)
    rows[dy + 1] = coarse_disparity.ptr<float>(std::clamp(cy + dy, coarse_y0, coarse_y1 - 1));
  for (int cx = 0; cx < width; ++cx) {
    int16_t* values = scratch.values.data() + static_cast<std::ptrdiff_t>(cx) * kNeighbourhood;
    int n = 0;
    for (const float* row : rows) {
      for (int x = std::max(0, cx - 1); x <= std::min(width - 1, cx + 1); ++x) {
        if (std::isfinite(row[x])) values[n++] = static_cast<int16_t>(row[x]);
      }
    }
    std::sort(values, values + n);
    n = static_cast<int>(std::unique(values, values + n) - values);
    scratch.counts[cx] = static_cast<uint8_t>(n);
    if (n == 0) {
      scratch.centres[cx] = kNoCentre;
    } else if (scale * (values[n - 1] - values[0]) <= kSpan) {
      scratch.centres[cx] = scale * (values[0] + values[n - 1]) / 2;
    } else {
      scratch.centres[cx] = kEdge;
    }
  }
}

// 5x5 SAD between left pixel (x, y) and right pixel (x - d, y), for -kEdgeCheckRadius <= d <= x:
// both windows lie inside the images' borders. On x86 one PSADBW per row, over 8 loaded bytes of
// which the last 3 are masked out (the rows' borders and the rows below keep those reads inside
// the image memory).
int windowSad(const EdgeCheckImages& im, int x, int y, int d) {
  const uint8_t* left = im.left + (y - kEdgeCheckRadius) * im.stride + x - kEdgeCheckRadius;
  const uint8_t* right = left - im.left + im.right - d;
  constexpr int kSide = 2 * kEdgeCheckRadius + 1;
#if defined(__SSE2__)
  const __m128i mask = _mm_set_epi32(0, 0, 0x000000FF, -1);  // bytes 0..4
  __m128i sum = _mm_setzero_si128();
  for (int wy = 0; wy < kSide; ++wy, left += im.stride, right += im.stride) {
    const __m128i l = _mm_and_si128(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(left)), mask);
    const __m128i r = _mm_and_si128(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(right)), mask);
    sum = _mm_add_epi64(sum, _mm_sad_epu8(l, r));
  }
  return _mm_cvtsi128_si32(sum);
#else
  int sum = 0;
  for (int wy = 0; wy < kSide; ++wy, left += im.stride, right += im.stride) {
    for (int wx = 0; wx < kSide; ++wx) sum += std::abs(left[wx] - right[wx]);
  }
  return sum;
#endif
}

// The band centre of full-size pixel (x, y) at a depth edge, from its neighbourhood's distinct
// coarse disparities `values` (ascending, n > 0): see band_placement.h.
int edgeCentre(const EdgeCheckImages& im, int scale, int x, int y, const int16_t* values, int n) {
  int winner = values[0], best = INT_MAX;
  for (int i = 0; i < n; ++i) {
    const int centre = scale * values[i];
    for (int d = centre - scale / 2; d <= std::min(centre + scale / 2, x); ++d) {
      const int sad = windowSad(im, x, y, d);
      if (sad < best) {
        best = sad;
        winner = values[i];
      }
    }
  }
  // The window [a, a + kSpan / scale] that holds the winner and the most values.
  int best_count = 0, lo = winner, hi = winner;
  for (int i = 0; i < n && values[i] <= winner; ++i) {
    if (scale * (winner - values[i]) > kSpan) continue;
    int count = 0, top = values[i];
    for (int j = i; j < n && scale * (values[j] - values[i]) <= kSpan; ++j) {
      ++count;
      top = values[j];
    }
    if (count > best_count) {
      best_count = count;
      lo = values[i];
      hi = top;
    }
  }
  return scale * (lo + hi) / 2;
}

}  // namespace

void placeBands(const cv::Mat& coarse_disparity, const StereoConfig& config, const EdgeCheckImages& images, int coarse_y0,
                int coarse_y1, int y0, int y1, BandScratch& scratch, cv::Mat& band_start) {
  const int scale = config.coarse_scale;
  const int width = images.width;
  for (int y = y0; y < y1; ++y) {
    int16_t* out = band_start.ptr<int16_t>(y);
    if (y == y0 || y % scale == 0) coarseRowCentres(coarse_disparity, scale, coarse_y0, coarse_y1, y / scale, scratch);
    for (int x = 0; x < width; ++x) {
      const int cx = x / scale;
      int centre = scratch.centres[cx];
      // A band of the first columns holds all their disparities with a right pixel, wherever it is centred.
      const bool forced = x - config.min_disparity_px + 1 <= kBandDisparities;
      if (centre == kEdge && forced) {
        centre = kNoCentre;
      } else if (centre == kEdge) {
        centre = edgeCentre(images, scale, x, y, scratch.values.data() + static_cast<std::ptrdiff_t>(cx) * kNeighbourhood,
                            scratch.counts[cx]);
      }
      out[x] = static_cast<int16_t>(centre == kNoCentre ? config.bandStart(INFINITY, x)
                                                        : config.bandStartAround(centre, x));
    }
  }
}

}  // namespace cenote::pipeline::detail
