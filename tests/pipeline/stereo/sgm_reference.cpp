#include "tests/pipeline/stereo/sgm_reference.h"

#include "pipeline/stereo/stereo_matcher.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace cenote::test {
namespace {

using pipeline::StereoConfig;

struct Volume {
  int W, H, D;
  std::vector<int> v;
  Volume(int w, int h, int d) : W(w), H(h), D(d), v(static_cast<size_t>(w) * h * d, 0) {}
  int& at(int x, int y, int k) { return v[(static_cast<size_t>(y) * W + x) * D + k]; }
};

uint8_t pixel(const cv::Mat& img, int x, int y) {
  return img.at<uint8_t>(std::clamp(y, 0, img.rows - 1), std::clamp(x, 0, img.cols - 1));
}

uint32_t census(const cv::Mat& img, int x, int y, int window) {
  const int r = window / 2;
  uint32_t bits = 0;
  for (int dy = -r; dy <= r; ++dy) {
    for (int dx = -r; dx <= r; ++dx) {
      if (dx == 0 && dy == 0) continue;
      bits = (bits << 1) | (pixel(img, x + dx, y + dy) < pixel(img, x, y) ? 1u : 0u);
    }
  }
  return bits;
}

Volume matchingCost(const cv::Mat& L, const cv::Mat& R, const StereoConfig& c) {
  const int W = L.cols, H = L.rows, D = c.num_disparities, r = c.window_px / 2;
  Volume cost(W, H, D);
  for (int y = 0; y < H; ++y) {
    for (int x = 0; x < W; ++x) {
      for (int k = 0; k < D; ++k) {
        const int d = c.min_disparity_px + k;
        int value = 0;
        if (x - d < 0) {
          value = c.maxCost();
        } else if (c.cost == pipeline::MatchingCost::kCensus) {
          value = __builtin_popcount(census(L, x, y, c.window_px) ^ census(R, x - d, y, c.window_px));
        } else {
          for (int i = -r; i <= r; ++i) {
            for (int j = -r; j <= r; ++j) {
              const int column = std::clamp(x + j, 0, W - 1);
              // Right pixels left of the image repeat column 0.
              value += std::abs(pixel(L, column, y + i) - pixel(R, std::max(column - d, 0), y + i));
            }
          }
          value >>= c.sadShift();
        }
        cost.at(x, y, k) = value;
      }
    }
  }
  return cost;
}

int adaptedP2(const StereoConfig& c, int gradient) {
  if (!c.adaptive_p2) return c.effectiveP2();
  int value = static_cast<int>(std::lround(c.effectiveP2() / (1.0 + gradient / c.p2_gradient_scale)));
  return std::min(std::max(value, c.effectiveP1() + 1), c.effectiveP2());
}

// Band of searched disparities per pixel: [start, start + width). The full search is one band.
struct Bands {
  cv::Mat start;  // CV_32S, empty: every pixel starts at 0
  int width = 0;
  int lo(int x, int y) const { return start.empty() ? 0 : start.at<int>(y, x); }
};

constexpr int kInfinite = 1 << 28;  // path cost outside a pixel's band

// Adds the path costs along direction (rx, ry) to `sums`. Pixels are visited so that the
// predecessor (x - rx, y - ry) always comes first. Outside a pixel's band its path costs are
// infinite (and its sums are never read).
void aggregate(const Volume& cost, const cv::Mat& L, const StereoConfig& c, const Bands& bands, int rx, int ry,
               Volume& sums) {
  const int W = cost.W, H = cost.H, D = cost.D, P1 = c.effectiveP1();
  Volume path(W, H, D);
  std::fill(path.v.begin(), path.v.end(), kInfinite);
  const int y0 = ry >= 0 ? 0 : H - 1, ystep = ry >= 0 ? 1 : -1;
  const int x0 = rx >= 0 ? 0 : W - 1, xstep = rx >= 0 ? 1 : -1;
  for (int y = y0; y >= 0 && y < H; y += ystep) {
    for (int x = x0; x >= 0 && x < W; x += xstep) {
      const int px = x - rx, py = y - ry;
      const bool has_prev = px >= 0 && px < W && py >= 0 && py < H && !(rx == 0 && ry == 0);
      int min_prev = std::numeric_limits<int>::max();
      if (has_prev) {
        for (int k = 0; k < D; ++k) min_prev = std::min(min_prev, path.at(px, py, k));
      }
      const int P2 = has_prev ? adaptedP2(c, std::abs(pixel(L, x, y) - pixel(L, px, py))) : 0;
      const int lo = bands.lo(x, y);
      for (int k = lo; k < lo + bands.width; ++k) {
        int value = const_cast<Volume&>(cost).at(x, y, k);
        if (has_prev) {
          int best = path.at(px, py, k);
          if (k > 0) best = std::min(best, path.at(px, py, k - 1) + P1);
          if (k + 1 < D) best = std::min(best, path.at(px, py, k + 1) + P1);
          best = std::min(best, min_prev + P2);
          value += best - min_prev;
        }
        path.at(x, y, k) = value;
        sums.at(x, y, k) += value;
      }
    }
  }
}

pipeline::DisparityMap match(const cv::Mat& L, const cv::Mat& R, const StereoConfig& c, const Bands& bands);

// 5x5 SAD of left pixel (x, y) against right pixel (x - d, y), replicated borders.
int windowSad(const cv::Mat& L, const cv::Mat& R, int x, int y, int d) {
  int sum = 0;
  for (int dy = -2; dy <= 2; ++dy) {
    for (int dx = -2; dx <= 2; ++dx) sum += std::abs(pixel(L, x + dx, y + dy) - pixel(R, x + dx - d, y + dy));
  }
  return sum;
}

// A band around the coarse disparities `near` (distinct, ascending) of a pixel at a depth edge:
// the value whose disparities s v - s / 2 .. s v + s / 2 (those <= x) hold the pixel's best 5x5
// SAD (the smaller value on ties), and with it as many of `near` as fit (the lowest window on ties).
int edgeBandCentre(const cv::Mat& L, const cv::Mat& R, const std::vector<int>& near, int s, int x, int y, int span) {
  int winner = near.front(), best = std::numeric_limits<int>::max();
  for (const int v : near) {
    for (int d = s * v - s / 2; d <= std::min(s * v + s / 2, x); ++d) {  // disparities with a right pixel
      const int sad = windowSad(L, R, x, y, d);
      if (sad < best) {
        best = sad;
        winner = v;
      }
    }
  }
  int best_count = 0, lo = winner, hi = winner;
  for (const int a : near) {
    if (a > winner || s * (winner - a) > span) continue;
    std::vector<int> covered;
    for (const int v : near) {
      if (v >= a && s * (v - a) <= span) covered.push_back(v);
    }
    if (static_cast<int>(covered.size()) > best_count) {
      best_count = static_cast<int>(covered.size());
      lo = a;
      hi = covered.back();
    }
  }
  return s * (lo + hi) / 2;
}

// Coarse to fine: the match of the shrunk pair (StereoConfig::coarseConfig, shrinkImage) places
// each pixel's band (StereoConfig::bandStart). These shared helpers are plain scalar code; the
// coarse match itself is this file's own.
Bands bandsFromCoarseMatch(const cv::Mat& L, const cv::Mat& R, const StereoConfig& c) {
  const StereoConfig coarse = c.coarseConfig();
  cv::Mat coarse_left, coarse_right;
  pipeline::shrinkImage(L, c.coarse_scale, coarse_left);
  pipeline::shrinkImage(R, c.coarse_scale, coarse_right);
  const cv::Mat coarse_disparity = match(coarse_left, coarse_right, coarse, Bands{{}, coarse.num_disparities}).disparity;
  // The edge check compares what SAD compares (census: the grey images).
  const bool sad = c.cost == pipeline::MatchingCost::kSad;
  const cv::Mat check_left = sad ? pipeline::prefilterForSad(L, c.prefilter, c.prefilter_cap) : L;
  const cv::Mat check_right = sad ? pipeline::prefilterForSad(R, c.prefilter, c.prefilter_cap) : R;
  Bands bands{cv::Mat(L.size(), CV_32S), pipeline::kBandDisparities};
  const int s = c.coarse_scale;
  const int span = pipeline::kBandDisparities - 4;  // 2 px to spare on each side
  for (int y = 0; y < L.rows; ++y) {
    for (int x = 0; x < L.cols; ++x) {
      // The band covers the 3x3 coarse neighbourhood's disparities when they fit with 2 px to
      // spare on each side, else (a depth edge) the candidate that the pixel's own SAD prefers
      // (its own coarse disparity where the output is invalidated as truncated).
      std::vector<int> near;
      for (int cy = y / s - 1; cy <= y / s + 1; ++cy) {
        for (int cx = x / s - 1; cx <= x / s + 1; ++cx) {
          const float d = coarse_disparity.at<float>(std::clamp(cy, 0, coarse_disparity.rows - 1),
                                                     std::clamp(cx, 0, coarse_disparity.cols - 1));
          if (std::isfinite(d)) near.push_back(static_cast<int>(d));
        }
      }
      std::sort(near.begin(), near.end());
      near.erase(std::unique(near.begin(), near.end()), near.end());
      int& start = bands.start.at<int>(y, x);
      if (near.empty()) {
        start = c.bandStart(INFINITY, x);
      } else if (s * (near.back() - near.front()) <= span) {
        start = c.bandStartAround(s * (near.front() + near.back()) / 2, x);
      } else if (c.invalidate_truncated && x < c.min_disparity_px + c.num_disparities - 1) {
        start = c.bandStart(coarse_disparity.at<float>(y / s, x / s), x);  // output invalid: own coarse disparity
      } else {
        start = c.bandStartAround(edgeBandCentre(check_left, check_right, near, s, x, y, span), x);
      }
    }
  }
  return bands;
}

}  // namespace

namespace {

pipeline::DisparityMap match(const cv::Mat& L, const cv::Mat& R, const StereoConfig& c, const Bands& bands) {
  const int W = L.cols, H = L.rows, D = c.num_disparities;
  const bool sad = c.cost == pipeline::MatchingCost::kSad;
  const Volume cost = sad ? matchingCost(pipeline::prefilterForSad(L, c.prefilter, c.prefilter_cap),
                                         pipeline::prefilterForSad(R, c.prefilter, c.prefilter_cap), c)
                          : matchingCost(L, R, c);
  Volume sums(W, H, D);
  const int directions[8][2] = {{1, 0}, {0, 1}, {1, 1}, {-1, 1}, {-1, 0}, {0, -1}, {-1, -1}, {1, -1}};
  for (int i = 0; i < c.num_paths; ++i) aggregate(cost, L, c, bands, directions[i][0], directions[i][1], sums);

  pipeline::DisparityMap out;
  out.disparity.create(H, W, CV_32F);
  out.confidence.create(H, W, CV_32F);
  const float inf = std::numeric_limits<float>::infinity();
  for (int y = 0; y < H; ++y) {
    // Right image's winner per right pixel (smallest k on ties), for the LR check.
    std::vector<int> right_best(W, std::numeric_limits<int>::max()), right_arg(W, 0);
    for (int x = 0; x < W; ++x) {
      for (int k = bands.lo(x, y); k < bands.lo(x, y) + bands.width; ++k) {
        const int xr = x - c.min_disparity_px - k;
        if (xr < 0) continue;
        const int s = sums.at(x, y, k);
        if (s < right_best[xr] || (s == right_best[xr] && k < right_arg[xr])) {
          right_best[xr] = s;
          right_arg[xr] = k;
        }
      }
    }
    for (int x = 0; x < W; ++x) {
      float& disparity = out.disparity.at<float>(y, x);
      float& confidence = out.confidence.at<float>(y, x);
      disparity = inf;
      confidence = 0.0f;
      const int valid = std::min(D, x - c.min_disparity_px + 1);
      if (valid <= 0 || (c.invalidate_truncated && valid < D)) continue;
      // Searched: the band's disparities that have a right pixel.
      const int first = bands.lo(x, y), end = std::min(valid, first + bands.width);
      if (end <= first) continue;
      int winner = first;
      for (int k = first + 1; k < end; ++k) {
        if (sums.at(x, y, k) < sums.at(x, y, winner)) winner = k;
      }
      const int c1 = sums.at(x, y, winner);
      const int reach = c.pkrn_exclude_neighbours ? 1 : 0;
      int c2 = -1;
      for (int k = first; k < end; ++k) {
        if (std::abs(k - winner) <= reach) continue;
        if (c2 < 0 || sums.at(x, y, k) < c2) c2 = sums.at(x, y, k);
      }
      const float pkrn = c2 < 0 ? 1.0f : (c2 + 1.0f) / (c1 + 1.0f);
      if (pkrn < c.min_confidence) continue;
      if (c.lr_check && std::abs(right_arg[x - c.min_disparity_px - winner] - winner) > c.lr_max_diff_px) continue;
      float offset = 0.0f;
      if (c.subpixel && winner > first && winner + 1 < end) {
        const int below = sums.at(x, y, winner - 1), above = sums.at(x, y, winner + 1);
        const int denominator = below + above - 2 * c1;
        if (denominator > 0) offset = static_cast<float>(below - above) / (2.0f * denominator);
      }
      disparity = static_cast<float>(c.min_disparity_px + winner) + offset;
      confidence = pkrn;
    }
  }
  return out;
}

}  // namespace

pipeline::DisparityMap referenceSgm(const cv::Mat& L, const cv::Mat& R, const StereoConfig& c) {
  if (c.usesBand()) return match(L, R, c, bandsFromCoarseMatch(L, R, c));
  return match(L, R, c, Bands{{}, c.num_disparities});
}

}  // namespace cenote::test
