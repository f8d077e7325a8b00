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

// The edge check of one coarse pixel's block: up to kMaxBlock rows of up to kMaxBlock pixels
// (x0.., rows y0..), each pixel's best 5x5 SAD so far and the index of the neighbourhood value
// that gave it. Scores fit 16 bits (at most 25 x 255).
struct EdgeBlock {
  static constexpr int16_t kNone = INT16_MAX;
  alignas(16) int16_t best[kMaxBlock][8];
  alignas(16) int16_t winner[kMaxBlock][8];
  int x0, y0, rows, count;

  // Pixel (row r, i) keeps `sad` at value index k if it beats its best (strictly: the smaller value
  // wins ties, and values come in ascending order).
  void offer(int r, int i, int sad, int k) {
    if (sad < best[r][i]) {
      best[r][i] = static_cast<int16_t>(sad);
      winner[r][i] = static_cast<int16_t>(k);
    }
  }

  // Every pixel's 5x5 SAD at disparity d, offered for value index k; d <= x0 + kEdgeCheckBorder -
  // kEdgeCheckRadius, so that every window read lies inside the borders (the pixels with d > x
  // are passed over). On x86 the pixels share their window rows and columns: per image row one
  // 8-byte load of each image (columns x0 - 2 .. x0 + 5; bytes past the row's border are the next
  // row's, never used), absolute differences in 16-bit lanes, each output row's five window rows
  // added as a running sum, each pixel's five columns by shifts.
  void offerInside(const EdgeCheckImages& im, int d, int k) {
#if defined(__SSE2__)
    const uint8_t* left = im.left + (y0 - kEdgeCheckRadius) * im.stride + x0 - kEdgeCheckRadius;
    const uint8_t* right = left - im.left + im.right - d;
    const __m128i zero = _mm_setzero_si128();
    __m128i columns[kMaxBlock + kWindow - 1];
    for (int j = 0; j < rows + kWindow - 1; ++j, left += im.stride, right += im.stride) {
      const __m128i l = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(left));
      const __m128i r = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(right));
      columns[j] = _mm_unpacklo_epi8(_mm_or_si128(_mm_subs_epu8(l, r), _mm_subs_epu8(r, l)), zero);
    }
    // Pixel i takes part where d <= x0 + i.
    const __m128i pixel_x = _mm_add_epi16(_mm_set1_epi16(static_cast<int16_t>(x0)), _mm_setr_epi16(0, 1, 2, 3, 4, 5, 6, 7));
    const __m128i has_right = _mm_cmpgt_epi16(pixel_x, _mm_set1_epi16(static_cast<int16_t>(d - 1)));
    const __m128i value = _mm_set1_epi16(static_cast<int16_t>(k));
    __m128i window = columns[0];
    for (int j = 1; j < kWindow - 1; ++j) window = _mm_add_epi16(window, columns[j]);
    for (int r = 0; r < rows; ++r) {
      window = _mm_add_epi16(window, columns[r + kWindow - 1]);                // rows r .. r + 4
      const __m128i pairs = _mm_add_epi16(window, _mm_srli_si128(window, 2));  // columns i, i + 1
      const __m128i fours = _mm_add_epi16(pairs, _mm_srli_si128(pairs, 4));    // i .. i + 3
      const __m128i sads = _mm_add_epi16(fours, _mm_srli_si128(window, 8));    // i .. i + 4
      auto* best_r = reinterpret_cast<__m128i*>(best[r]);
      auto* winner_r = reinterpret_cast<__m128i*>(winner[r]);
      const __m128i better = _mm_and_si128(has_right, _mm_cmplt_epi16(sads, *best_r));
      *best_r = _mm_or_si128(_mm_and_si128(better, sads), _mm_andnot_si128(better, *best_r));
      *winner_r = _mm_or_si128(_mm_and_si128(better, value), _mm_andnot_si128(better, *winner_r));
      window = _mm_sub_epi16(window, columns[r]);
    }
#else
    offerEach(im, d, k);
#endif
  }

  // The same, pixel by pixel, for any d (those with d > x passed over).
  void offerEach(const EdgeCheckImages& im, int d, int k) {
    for (int r = 0; r < rows; ++r) {
      for (int i = 0; i < count; ++i) {
        if (d <= x0 + i) offer(r, i, windowSad(im, x0 + i, y0 + r, d), k);
      }
    }
  }
};

// Band centres of the block's pixels (one coarse pixel's, at a depth edge), from the
// neighbourhood's distinct coarse disparities `values` (ascending, n > 0): see band_placement.h.
// A disparity that two neighbouring values' ranges share is scored once, for the smaller value,
// which would win the tie anyway.
void edgeCentres(const EdgeCheckImages& im, int scale, EdgeBlock& block, const int16_t* values, int n,
                 int (&centres)[kMaxBlock][kMaxBlock]) {
  for (int r = 0; r < block.rows; ++r) {
    std::fill_n(block.best[r], 8, EdgeBlock::kNone);
    std::fill_n(block.winner[r], 8, 0);
  }
  const int last_x = block.x0 + block.count - 1;
  int scored = INT_MIN;  // the largest disparity scored so far
  for (int k = 0; k < n; ++k) {
    const int centre = scale * values[k];
    for (int d = std::max(centre - scale / 2, scored + 1); d <= std::min(centre + scale / 2, last_x); ++d) {
      if (d <= block.x0 + kEdgeCheckBorder - kEdgeCheckRadius) {
        block.offerInside(im, d, k);
      } else {
        block.offerEach(im, d, k);
      }
      scored = d;
    }
  }
  // The band around each winning value, once per value: the block's pixels mostly share a few.
  int window_of[kNeighbourhood];
  std::fill_n(window_of, n, kNoCentre);
  for (int r = 0; r < block.rows; ++r) {
    for (int i = 0; i < block.count; ++i) {
      const int k = block.winner[r][i];
      if (window_of[k] == kNoCentre) window_of[k] = windowAround(values, n, values[k], scale);
      centres[r][i] = window_of[k];
    }
  }
}

// Band starts of row `out` from the coarse row's centres (kNoCentre: from disparity 0; kEdge:
// any value, placeEdgeBlock() overwrites it): StereoConfig::bandStartAround() for every pixel,
// its range part once per coarse pixel and its border part on the columns it limits only.
void placeRow(const StereoConfig& config, const std::vector<int>& centres, int width, int16_t* out) {
  const int scale = config.coarse_scale;
  for (int cx = 0; cx < static_cast<int>(centres.size()); ++cx) {
    const int centre = centres[cx] == kNoCentre || centres[cx] == kEdge ? config.min_disparity_px : centres[cx];
    const int x0 = cx * scale;
    std::fill(out + x0, out + std::min(width, x0 + scale), static_cast<int16_t>(config.bandStartInRange(centre)));
  }
  for (int x = 0; x < std::min(width, config.min_disparity_px + config.num_disparities - 1); ++x) {
    out[x] = static_cast<int16_t>(std::min<int>(out[x], config.bandStartWithRightPixels(x)));
  }
}

// The band starts of edge coarse pixel cx in the strip's rows y .. y + rows - 1 of its coarse row.
void placeEdgeBlock(const cv::Mat& coarse_disparity, const StereoConfig& config, const EdgeCheckImages& images,
                    const BandScratch& scratch, int cx, int y, int rows, int truncated_end, cv::Mat& band_start) {
  const int scale = config.coarse_scale;
  EdgeBlock block;
  block.x0 = cx * scale;
  block.y0 = y;
  block.rows = rows;
  block.count = std::min(scale, images.width - block.x0);
  int centres[kMaxBlock][kMaxBlock];
  if (block.x0 + block.count - config.min_disparity_px <= kBandDisparities) {
    // Even the block's last column has a band holding all its disparities with a right pixel: the
    // centre does not matter (StereoConfig::bandStartAround()), no check.
    for (auto& row : centres) std::fill_n(row, kMaxBlock, kNoCentre);
  } else {
    if (block.x0 + block.count > truncated_end) {
      edgeCentres(images, scale, block, scratch.values.data() + static_cast<std::ptrdiff_t>(cx) * kNeighbourhood,
                  scratch.counts[cx], centres);
    }
    // Columns whose output is invalidated: the pixel's own coarse disparity.
    const float own = coarse_disparity.ptr<float>(y / scale)[cx];
    for (int i = 0; i < block.count && block.x0 + i < truncated_end; ++i) {
      for (int r = 0; r < rows; ++r) centres[r][i] = std::isfinite(own) ? scale * static_cast<int>(own) : kNoCentre;
    }
  }
  for (int r = 0; r < rows; ++r) {
    int16_t* out = band_start.ptr<int16_t>(y + r);
    for (int i = 0; i < block.count; ++i) {
      const int x = block.x0 + i;
      out[x] = static_cast<int16_t>(centres[r][i] == kNoCentre ? config.bandStart(INFINITY, x)
                                                               : config.bandStartAround(centres[r][i], x));
    }
  }
}

}  // namespace

void placeBands(const cv::Mat& coarse_disparity, const StereoConfig& config, const EdgeCheckImages& images, int coarse_y0,
                int coarse_y1, int y0, int y1, BandScratch& scratch, cv::Mat& band_start) {
  const int scale = config.coarse_scale;
  const int width = images.width;
  // Columns whose output the matcher invalidates (StereoConfig::invalidate_truncated) keep the
  // pixel's own coarse disparity at edges: their bands only feed the paths.
  const int truncated_end = config.invalidate_truncated ? config.min_disparity_px + config.num_disparities - 1 : 0;
  // The strip's rows of one coarse row at a time: they share their bands but at depth edges.
  for (int y = y0; y < y1;) {
    const int cy = y / scale;
    const int rows = std::min(y1, (cy + 1) * scale) - y;
    coarseRowCentres(coarse_disparity, scale, coarse_y0, coarse_y1, cy, scratch);
    int16_t* first = band_start.ptr<int16_t>(y);
    placeRow(config, scratch.centres, width, first);
    for (int r = 1; r < rows; ++r) std::copy_n(first, width, band_start.ptr<int16_t>(y + r));
    for (const int cx : scratch.edges) {
      placeEdgeBlock(coarse_disparity, config, images, scratch, cx, y, rows, truncated_end, band_start);
    }
    y += rows;
  }
}

}  // namespace cenote::pipeline::detail
