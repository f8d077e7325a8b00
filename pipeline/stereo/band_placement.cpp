#include "pipeline/stereo/band_placement.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace cenote::pipeline::detail {
namespace {

constexpr int kNoCentre = INT32_MIN;                       // no finite coarse disparity around
constexpr int kEdge = INT32_MIN + 1;                       // a depth edge: the centre is chosen per full-size pixel
constexpr int kNeighbourhood = 9;                          // values of a 3x3 neighbourhood
constexpr int kSpan = kBandDisparities - 2 * kBandMargin;  // full-size disparities a band covers with margins
constexpr int kWindow = 2 * kEdgeCheckRadius + 1;
constexpr int kMaxBlock = 4;  // full-size pixels of one coarse pixel in a row: the largest coarse_scale

// The band centre around `winner`: the window [a, a + kSpan / scale] of `values` (ascending) that
// holds the winner and the most values (the lowest such window on ties), centred.
int windowAround(const int16_t* values, int n, int winner, int scale) {
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

// The finite disparities of the three coarse rows at each column: their range and count, in
// loops the compiler vectorises (most coarse pixels need nothing more).
void columnRanges(const float* const (&rows)[3], int width, BandScratch& scratch) {
  scratch.column_lo.resize(width);
  scratch.column_hi.resize(width);
  scratch.column_finite.resize(width);
  float* lo = scratch.column_lo.data();
  float* hi = scratch.column_hi.data();
  uint8_t* finite = scratch.column_finite.data();
  constexpr float kMax = std::numeric_limits<float>::max();
  for (int x = 0; x < width; ++x) {
    float l = kMax, h = -kMax;
    uint8_t n = 0;
    for (const float* row : rows) {
      const float v = row[x];
      const bool ok = std::fabs(v) <= kMax;  // finite (NaN fails)
      l = ok && v < l ? v : l;
      h = ok && v > h ? v : h;
      n = static_cast<uint8_t>(n + (ok ? 1 : 0));
    }
    lo[x] = l;
    hi[x] = h;
    finite[x] = n;
  }
}

// Centres of coarse row cy, and for its edge pixels the neighbourhood's distinct values, ascending.
// The neighbourhood's range comes from the column ranges (truncation to integers keeps the order,
// so the range of the truncated values is the truncated range).
void coarseRowCentres(const cv::Mat& coarse_disparity, int scale, int coarse_y0, int coarse_y1, int cy,
                      BandScratch& scratch) {
  const int width = coarse_disparity.cols;
  scratch.centres.resize(width);
  scratch.values.resize(static_cast<std::size_t>(width) * kNeighbourhood);
  scratch.counts.resize(width);
  scratch.edges.clear();
  const float* rows[3];
  for (int dy = -1; dy <= 1; ++dy)
    rows[dy + 1] = coarse_disparity.ptr<float>(std::clamp(cy + dy, coarse_y0, coarse_y1 - 1));
  columnRanges(rows, width, scratch);
  for (int cx = 0; cx < width; ++cx) {
    const int x0 = std::max(0, cx - 1), x1 = std::min(width - 1, cx + 1);
    float lo_f = scratch.column_lo[x0], hi_f = scratch.column_hi[x0];
    int n = scratch.column_finite[x0];
    for (int x = x0 + 1; x <= x1; ++x) {
      lo_f = std::min(lo_f, scratch.column_lo[x]);
      hi_f = std::max(hi_f, scratch.column_hi[x]);
      n += scratch.column_finite[x];
    }
    if (n == 0) {
      scratch.centres[cx] = kNoCentre;
      continue;
    }
    const int lo = static_cast<int16_t>(lo_f), hi = static_cast<int16_t>(hi_f);
    if (scale * (hi - lo) <= kSpan) {
      scratch.centres[cx] = scale * (lo + hi) / 2;
      continue;
    }
    // A depth edge: the neighbourhood's distinct values, for edgeCentres().
    int16_t* values = scratch.values.data() + static_cast<std::ptrdiff_t>(cx) * kNeighbourhood;
    int count = 0;
    for (const float* row : rows) {
      for (int x = x0; x <= x1; ++x) {
        if (std::isfinite(row[x])) values[count++] = static_cast<int16_t>(row[x]);
      }
    }
    std::sort(values, values + count);
    scratch.counts[cx] = static_cast<uint8_t>(std::unique(values, values + count) - values);
    scratch.centres[cx] = kEdge;
    scratch.edges.push_back(cx);
  }
}

// 5x5 SAD between left pixel (x, y) and right pixel (x - d, y), for -kEdgeCheckRadius <= d <= x:
// both windows lie inside the images' borders.
int windowSad(const EdgeCheckImages& im, int x, int y, int d) {
  const uint8_t* left = im.left + (y - kEdgeCheckRadius) * im.stride + x - kEdgeCheckRadius;
  const uint8_t* right = left - im.left + im.right - d;
  int sum = 0;
  for (int wy = 0; wy < kWindow; ++wy, left += im.stride, right += im.stride) {
    for (int wx = 0; wx < kWindow; ++wx) sum += std::abs(left[wx] - right[wx]);
  }
  return sum;
}

// The 5x5 SADs at disparity d of the `count` (<= kMaxBlock) pixels x0.. of row y, into `sads`;
// d <= x0 + kEdgeCheckBorder - kEdgeCheckRadius, so that every window read lies inside the
// borders (a pixel's own d <= x rule is the caller's). On x86 the pixels share their columns:
// per window row one 8-byte load of each image (columns x0 - 2 .. x0 + 5; bytes past the row's
// border are the next row's, never used), absolute differences summed over the rows in 16-bit
// lanes, then each pixel's 5 columns added by shifts.
void blockSads(const EdgeCheckImages& im, int x0, int count, int y, int d, int* sads) {
#if defined(__SSE2__)
  const uint8_t* left = im.left + (y - kEdgeCheckRadius) * im.stride + x0 - kEdgeCheckRadius;
  const uint8_t* right = left - im.left + im.right - d;
  const __m128i zero = _mm_setzero_si128();
  __m128i columns = zero;
  for (int wy = 0; wy < kWindow; ++wy, left += im.stride, right += im.stride) {
    const __m128i l = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(left));
    const __m128i r = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(right));
    const __m128i diff = _mm_or_si128(_mm_subs_epu8(l, r), _mm_subs_epu8(r, l));
    columns = _mm_add_epi16(columns, _mm_unpacklo_epi8(diff, zero));
  }
  const __m128i pairs = _mm_add_epi16(columns, _mm_srli_si128(columns, 2));  // columns i, i + 1
  const __m128i fours = _mm_add_epi16(pairs, _mm_srli_si128(pairs, 4));      // i .. i + 3
  const __m128i fives = _mm_add_epi16(fours, _mm_srli_si128(columns, 8));    // i .. i + 4
  alignas(16) uint16_t lanes[8];
  _mm_store_si128(reinterpret_cast<__m128i*>(lanes), fives);
  for (int i = 0; i < count; ++i) sads[i] = lanes[i];
#else
  for (int i = 0; i < count; ++i) sads[i] = windowSad(im, x0 + i, y, d);
#endif
}

// Band centres of the `count` pixels x0.. of row y (one coarse pixel's, at a depth edge), from
// the neighbourhood's distinct coarse disparities `values` (ascending, n > 0): see
// band_placement.h.
void edgeCentres(const EdgeCheckImages& im, int scale, int x0, int count, int y, const int16_t* values, int n,
                 int* centres) {
  int winner[kMaxBlock], best[kMaxBlock], sads[kMaxBlock];
  for (int i = 0; i < count; ++i) {
    winner[i] = values[0];
    best[i] = INT_MAX;
  }
  const int last_x = x0 + count - 1;
  for (int k = 0; k < n; ++k) {
    const int centre = scale * values[k];
    for (int d = centre - scale / 2; d <= std::min(centre + scale / 2, last_x); ++d) {
      if (d <= x0 + kEdgeCheckBorder - kEdgeCheckRadius) {
        blockSads(im, x0, count, y, d, sads);
      } else {
        for (int i = 0; i < count; ++i) sads[i] = d <= x0 + i ? windowSad(im, x0 + i, y, d) : INT_MAX;
      }
      for (int i = 0; i < count; ++i) {
        if (d <= x0 + i && sads[i] < best[i]) {
          best[i] = sads[i];
          winner[i] = values[k];
        }
      }
    }
  }
  for (int i = 0; i < count; ++i) centres[i] = windowAround(values, n, winner[i], scale);
}

// The centres of the `count` pixels x0.. of row y in edge coarse pixel cx (`own` its coarse
// disparity times the scale), by the rules of band_placement.h.
void edgeBlockCentres(const EdgeCheckImages& images, const StereoConfig& config, const BandScratch& scratch, int cx, int x0,
                      int count, int y, int own, int truncated_end, int* centres) {
  if (x0 + count - config.min_disparity_px <= kBandDisparities) {
    // Even the block's last column has a band holding all its disparities with a right pixel: the
    // centre does not matter (StereoConfig::bandStartAround()), no check.
    std::fill_n(centres, count, kNoCentre);
    return;
  }
  if (x0 + count > truncated_end) {
    edgeCentres(images, config.coarse_scale, x0, count, y,
                scratch.values.data() + static_cast<std::ptrdiff_t>(cx) * kNeighbourhood, scratch.counts[cx], centres);
  }
  for (int i = 0; i < count && x0 + i < truncated_end; ++i) centres[i] = own;
}

}  // namespace

void placeBands(const cv::Mat& coarse_disparity, const StereoConfig& config, const EdgeCheckImages& images, int coarse_y0,
                int coarse_y1, int y0, int y1, BandScratch& scratch, cv::Mat& band_start) {
  const int scale = config.coarse_scale;
  const int width = images.width;
  // Columns whose output the matcher invalidates (StereoConfig::invalidate_truncated) keep the
  // pixel's own coarse disparity at edges: their bands only feed the paths.
  const int truncated_end = config.invalidate_truncated ? config.min_disparity_px + config.num_disparities - 1 : 0;
  int centres[kMaxBlock];
  // The pixels of coarse pixel cx in row y.
  auto placeBlock = [&](int y, int cx, int16_t* out) {
    const int x0 = cx * scale, count = std::min(scale, width - x0);
    std::fill_n(centres, count, scratch.centres[cx]);
    if (scratch.centres[cx] == kEdge) {
      const float own = coarse_disparity.ptr<float>(y / scale)[cx];
      edgeBlockCentres(images, config, scratch, cx, x0, count, y,
                       std::isfinite(own) ? scale * static_cast<int>(own) : kNoCentre, truncated_end, centres);
    }
    for (int i = 0; i < count; ++i) {
      const int x = x0 + i;
      out[x] = static_cast<int16_t>(centres[i] == kNoCentre ? config.bandStart(INFINITY, x)
                                                            : config.bandStartAround(centres[i], x));
    }
  };
  const int coarse_width = coarse_disparity.cols;
  for (int y = y0; y < y1; ++y) {
    int16_t* out = band_start.ptr<int16_t>(y);
    if (y == y0 || y % scale == 0) {
      coarseRowCentres(coarse_disparity, scale, coarse_y0, coarse_y1, y / scale, scratch);
      for (int cx = 0; cx < coarse_width; ++cx) placeBlock(y, cx, out);
    } else {  // the rows of one coarse row share their bands but at depth edges
      std::copy_n(band_start.ptr<int16_t>(y - 1), width, out);
      for (const int cx : scratch.edges) placeBlock(y, cx, out);
    }
  }
}

}  // namespace cenote::pipeline::detail
