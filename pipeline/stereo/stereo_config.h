// stereo_config.h: settings of StereoMatcher. Disparities are in pixels of the rectified left image;
// costs are in the matcher's integer cost units (SAD: grey levels summed over the window, shifted
// right so that the largest window cost stays <= 4095; census: Hamming distance in bits).
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "common/config_error.h"

namespace cenote {
class YamlSection;
}

namespace cenote::pipeline {

enum class MatchingCost { kSad, kCensus };

// What SAD compares. kNone: grey levels (the paper's cost). kSobelX: the horizontal derivative,
// clipped to +-prefilter_cap (as OpenCV's StereoSGBM): blind to brightness offsets between the
// cameras and far better on Middlebury Motorcycle (tests/pipeline/stereo/middlebury_test.cpp).
enum class Prefilter { kNone, kSobelX };

// Which disparities each pixel searches. kFull: all num_disparities. kBand: coarse to fine (as
// tSGM): full SGM on the pair shrunk by coarse_scale, then at full size each pixel searches
// kBandDisparities around coarse_scale times the coarse disparities of its 3x3 coarse
// neighbourhood; where those do not fit in one band (a depth edge), around the ones that the
// pixel's own 5x5 SAD prefers (band_placement.h). Path costs outside a pixel's band count as
// infinite. Ranges of at most kBandDisparities are always searched in full.
enum class SearchMode { kFull, kBand };
inline constexpr int kBandDisparities = 32;

struct StereoConfig {
  MatchingCost cost = MatchingCost::kSad;
  int num_disparities = 112;                 // search range size; a multiple of 16 in [16, 512]
  int min_disparity_px = 0;                  // first disparity searched; >= 0
  int window_px = 3;                         // SAD: odd side in [1, 9]; census: 3 or 5
  Prefilter prefilter = Prefilter::kSobelX;  // SAD only
  int prefilter_cap = 63;                    // derivative clipped to +-cap grey levels, in [1, 127]; 63 keeps the
                                             // sub-pixel error of a slanted plane at 0.13 px (31: 0.15)
  int num_paths = 4;                         // SGM: 4 = one top-down pass (rSGM), 8 = two passes
  SearchMode search = SearchMode::kBand;     // band around a coarse match (about 2.3x faster), or full
  int coarse_scale = 4;                      // kBand: the coarse match runs on the pair shrunk by 2 or 4 (2x2 or
                                             // 4x4 means); 4 costs a sixteenth of the full size instead of a
                                             // quarter, for nearly the same accuracy (middlebury_test.cpp)
  int p1 = -1;                               // penalty for a disparity step of 1; -1 = default of the cost
  int p2 = -1;                               // penalty for larger steps; -1 = default of the cost
  bool adaptive_p2 = false;                  // P2 / (1 + |I(p) - I(p-r)| / p2_gradient_scale), never below P1 + 1
  double p2_gradient_scale = 8.0;            // grey levels; only with adaptive_p2
  bool subpixel = true;                      // parabola through the aggregated costs at d-1, d, d+1
  bool pkrn_exclude_neighbours = true;       // second minimum taken outside d*-1..d*+1 (see stereo_matcher.h)
  double min_confidence = 0.0;               // PKRN below this marks the pixel invalid; PKRN >= 1, so 0 keeps all
  bool lr_check = true;                      // left-right consistency check on integer disparities (mapping wants
                                             // few, right points; config/default.yaml documents every default)
  bool invalidate_truncated = true;          // mark invalid the left columns x < min_d + D - 1, whose
                                             // search range is cut by the image border: their true match may lie
                                             // outside the right image (OpenCV's behaviour; for mapping)
  int lr_max_diff_px = 1;                    // allowed |d_left - d_right| with lr_check
  int num_strips = 2;                        // fixed horizontal strips matched independently (threads share them);
                                             // fixed so that the result does not depend on the thread count
  int strip_overlap_px = 24;                 // rows matched above (and below, 8 paths) a strip before its own rows,
                                             // so that vertical paths arrive warmed up at the strip border

  // Penalties with the per-cost defaults resolved.
  int effectiveP1() const;
  int effectiveP2() const;
  // Largest cost of one pixel and disparity in cost units.
  int maxCost() const;
  // Whether the sum of `paths` path costs, each at most maxCost() + P1 + P2, fits the engine's 16 bits.
  bool pathSumFits(int paths) const;
  // True when matching uses the coarse-to-fine band (kBand and a range wider than the band).
  bool usesBand() const;
  // kBand: the settings of the coarse match. Disparities divided by coarse_scale (the range rounded
  // outwards), the same penalties, 8 paths (unless their sum would overflow 16 bits), integer
  // winners only and none of the checks that would leave a pixel without a band; full search. Its
  // range need not be a multiple of 16: not for validate().
  StereoConfig coarseConfig() const;
  // kBand: the first disparity index (from min_disparity_px) of a band of full-size column x
  // around coarse disparity coarse_disparity_px (+inf: none, the band starts at 0). The matcher
  // centres a pixel's band on its 3x3 coarse neighbourhood where that fits (bandStartAround()).
  // The band is centred on coarse_scale * coarse_disparity_px, kept inside the range and, where
  // the image border cuts the range, on the disparities that have a right pixel.
  int bandStart(float coarse_disparity_px, int x) const {  // inline: called per pixel
    return bandStartAround(
        std::isfinite(coarse_disparity_px) ? coarse_scale * static_cast<int>(coarse_disparity_px) : min_disparity_px, x);
  }
  // The band of column x centred on disparity centre_px (full-size pixels), placed as bandStart().
  int bandStartAround(int centre_px, int x) const {
    return std::min(bandStartInRange(centre_px), bandStartWithRightPixels(x));
  }
  // The band centred on centre_px, kept inside the range (any column's, before the border's rule).
  int bandStartInRange(int centre_px) const {
    return std::clamp(centre_px - min_disparity_px - kBandDisparities / 2, 0, num_disparities - kBandDisparities);
  }
  // The largest start whose band holds only disparities with a right pixel in column x; at least
  // num_disparities - kBandDisparities (no limit) from column min_d + num_disparities - 1 on.
  int bandStartWithRightPixels(int x) const { return std::max(0, x - min_disparity_px + 1 - kBandDisparities); }
  // Right shift applied to SAD window sums so that maxCost() <= 4095.
  int sadShift() const;
  // Largest difference of one pixel pair that SAD sees (255, or 2 * prefilter_cap).
  int sadPixelRange() const;

  // Every failed rule, empty when valid.
  std::vector<ConfigError> validate() const;
  // Reads keys of a `stereo:` section; unknown keys are errors.
  void read(YamlSection& section);
};

const char* toString(MatchingCost cost);
const char* toString(Prefilter prefilter);
const char* toString(SearchMode search);
// @throws cenote::Error for anything but "full" or "band".
SearchMode parseSearchMode(const std::string& name);
// @throws cenote::Error for anything but "none" or "sobel_x".
Prefilter parsePrefilter(const std::string& name);
// @throws cenote::Error for anything but "sad" or "census".
MatchingCost parseMatchingCost(const std::string& name);

}  // namespace cenote::pipeline
