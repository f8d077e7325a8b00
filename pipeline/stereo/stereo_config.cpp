#include "pipeline/stereo/stereo_config.h"

#include "common/enum_names.h"
#include "common/error.h"
#include "common/yaml_section.h"

namespace cenote::pipeline {
namespace {

// Census window side -> number of comparison bits (every pixel but the centre).
int censusBits(int window_px) { return window_px * window_px - 1; }

}  // namespace

bool StereoConfig::usesBand() const { return search == SearchMode::kBand && num_disparities > kBandDisparities; }

StereoConfig StereoConfig::coarseConfig() const {
  StereoConfig coarse = *this;
  coarse.search = SearchMode::kFull;
  coarse.min_disparity_px = min_disparity_px / coarse_scale;
  coarse.num_disparities = (min_disparity_px + num_disparities + coarse_scale - 1) / coarse_scale - coarse.min_disparity_px;
  coarse.subpixel = false;
  coarse.lr_check = false;
  coarse.invalidate_truncated = false;
  coarse.min_confidence = 0.0;
  coarse.p1 = effectiveP1();
  coarse.p2 = effectiveP2();
  // Eight paths where their sum fits 16 bits (validate()): at a sixteenth of the pixels the second
  // pass costs little, and its winners place far fewer bands wrongly (middlebury_test.cpp).
  if (coarse.pathSumFits(8)) coarse.num_paths = 8;
  return coarse;
}

bool StereoConfig::pathSumFits(int paths) const {
  return static_cast<long>(paths) * (maxCost() + effectiveP1() + effectiveP2()) <= 65535;
}

int StereoConfig::sadPixelRange() const { return prefilter == Prefilter::kSobelX ? 2 * prefilter_cap : 255; }

int StereoConfig::sadShift() const {
  int shift = 0;
  while (((window_px * window_px * sadPixelRange()) >> shift) > 4095) ++shift;
  return shift;
}

int StereoConfig::maxCost() const {
  if (cost == MatchingCost::kCensus) return censusBits(window_px);
  return (window_px * window_px * sadPixelRange()) >> sadShift();
}

// Defaults from a sweep on Middlebury cones, Cloth3 and Motorcycle (bad-1 / bad-2 of
// tests/pipeline/stereo/middlebury_test.cpp); the penalties scale with the window area, as
// OpenCV's 8*w*w / 32*w*w do for its own cost. SAD 3x3: P1 = 90, P2 = 720 on the derivative,
// 360 on grey levels; census 5x5: P1 = 10, P2 = 30.
int StereoConfig::effectiveP1() const {
  if (p1 >= 0) return p1;
  if (cost == MatchingCost::kCensus) return (5 * censusBits(window_px) + 6) / 12;
  return std::max(1, (10 * window_px * window_px) >> sadShift());
}

int StereoConfig::effectiveP2() const {
  if (p2 >= 0) return p2;
  if (cost == MatchingCost::kCensus) return (5 * censusBits(window_px) + 2) / 4;
  const int per_area = prefilter == Prefilter::kSobelX ? 80 : 40;
  return std::max(2, (per_area * window_px * window_px) >> sadShift());
}

std::vector<ConfigError> StereoConfig::validate() const {
  ConfigErrors errors("stereo");
  errors.check(num_disparities >= 16 && num_disparities <= 512 && num_disparities % 16 == 0, "num_disparities",
               num_disparities, "must be a multiple of 16 in [16, 512]");
  errors.checkRange("min_disparity_px", min_disparity_px, 0, 4096);
  if (cost == MatchingCost::kSad) {
    errors.check(window_px >= 1 && window_px <= 9 && window_px % 2 == 1, "window_px", window_px,
                 "SAD window must be odd in [1, 9]");
  } else {
    errors.check(window_px == 3 || window_px == 5, "window_px", window_px, "census window must be 3 or 5");
  }
  errors.checkRange("prefilter_cap", prefilter_cap, 1, 127);
  errors.check(num_paths == 4 || num_paths == 8, "num_paths", num_paths, "must be 4 or 8");
  errors.check(coarse_scale == 2 || coarse_scale == 4, "coarse_scale", coarse_scale, "must be 2 or 4");
  errors.check(p1 >= -1, "p1", p1, "must be >= 0 (or -1 for the default)");
  errors.check(p2 >= -1, "p2", p2, "must be >= 0 (or -1 for the default)");
  const bool window_ok = window_px >= 1 && window_px <= 9 && prefilter_cap >= 1 && prefilter_cap <= 127;
  if (p1 >= -1 && p2 >= -1 && window_ok) {
    errors.check(effectiveP2() >= effectiveP1(), "p2", effectiveP2(),
                 "must be >= p1 (" + std::to_string(effectiveP1()) + ")");
    errors.check(pathSumFits(num_paths), "p2", effectiveP2(),
                 "num_paths * (max cost " + std::to_string(maxCost()) + " + p1 + p2) must be <= 65535");
  }
  errors.check(p2_gradient_scale > 0.0, "p2_gradient_scale", p2_gradient_scale, "must be > 0");
  errors.check(min_confidence >= 0.0, "min_confidence", min_confidence, "must be >= 0");
  errors.check(lr_max_diff_px >= 0, "lr_max_diff_px", lr_max_diff_px, "must be >= 0");
  errors.checkRange("num_strips", num_strips, 1, 64);
  errors.checkRange("strip_overlap_px", strip_overlap_px, 0, 256);
  return errors.take();
}

void StereoConfig::read(YamlSection& section) {
  section.readName("cost", cost, parseMatchingCost);
  section.read("num_disparities", num_disparities);
  section.read("min_disparity_px", min_disparity_px);
  section.read("window_px", window_px);
  section.readName("prefilter", prefilter, parsePrefilter);
  section.read("prefilter_cap", prefilter_cap);
  section.read("num_paths", num_paths);
  section.readName("search", search, parseSearchMode);
  section.read("coarse_scale", coarse_scale);
  section.read("p1", p1);
  section.read("p2", p2);
  section.read("adaptive_p2", adaptive_p2);
  section.read("p2_gradient_scale", p2_gradient_scale);
  section.read("subpixel", subpixel);
  section.read("pkrn_exclude_neighbours", pkrn_exclude_neighbours);
  section.read("min_confidence", min_confidence);
  section.read("lr_check", lr_check);
  section.read("invalidate_truncated", invalidate_truncated);
  section.read("lr_max_diff_px", lr_max_diff_px);
  section.read("num_strips", num_strips);
  section.read("strip_overlap_px", strip_overlap_px);
}

constexpr EnumName<MatchingCost> kCostNames[] = {{MatchingCost::kSad, "sad"}, {MatchingCost::kCensus, "census"}};
constexpr EnumName<Prefilter> kPrefilterNames[] = {{Prefilter::kNone, "none"}, {Prefilter::kSobelX, "sobel_x"}};
constexpr EnumName<SearchMode> kSearchNames[] = {{SearchMode::kFull, "full"}, {SearchMode::kBand, "band"}};

const char* toString(MatchingCost cost) { return enumName(kCostNames, cost); }

const char* toString(Prefilter prefilter) { return enumName(kPrefilterNames, prefilter); }

const char* toString(SearchMode search) { return enumName(kSearchNames, search); }

SearchMode parseSearchMode(const std::string& name) {
  return parseEnumName(kSearchNames, name, "stereo.search = " + name, NameQuotes::kSingle);
}

Prefilter parsePrefilter(const std::string& name) {
  return parseEnumName(kPrefilterNames, name, "stereo.prefilter = " + name, NameQuotes::kSingle);
}

MatchingCost parseMatchingCost(const std::string& name) {
  return parseEnumName(kCostNames, name, "stereo.cost = " + name, NameQuotes::kSingle);
}

}  // namespace cenote::pipeline
