#include "pipeline/stereo/stereo_matcher.h"

#include <gtest/gtest.h>
#include <hwy/targets.h>
#include <omp.h>

#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <random>

#include "common/error.h"
#include "pipeline/stereo/sgm_engine.h"
#include "tests/pipeline/stereo/sgm_reference.h"
#include "tests/support/test_data.h"
#include "tests/support/error_message.h"

namespace cenote::pipeline {
namespace {

// A textured pair: smooth random texture, the right image shifted by a known disparity field.
struct SyntheticPair {
  cv::Mat left, right;  // CV_8U
  cv::Mat disparity;    // CV_32F, true disparity of the left view
};

cv::Mat randomTexture(int width, int height, uint32_t seed) {
  cv::Mat texture(height, width, CV_32F);
  cv::RNG rng(seed);
  rng.fill(texture, cv::RNG::UNIFORM, 0.0, 255.0);
  cv::GaussianBlur(texture, texture, cv::Size(0, 0), 1.2);
  cv::normalize(texture, texture, 20, 235, cv::NORM_MINMAX);
  return texture;
}

// A slanted plane: d(x, y) = d0 + a x + b y; the right image samples the left texture at x - d
// (bilinear on a 4x oversampled texture, so sub-pixel shifts are real).
SyntheticPair slantedPlane(int width, int height, double d0, double a, double b, uint32_t seed) {
  const cv::Mat texture = randomTexture(width * 2, height, seed);
  SyntheticPair pair;
  pair.left.create(height, width, CV_8U);
  pair.right.create(height, width, CV_8U);
  pair.disparity.create(height, width, CV_32F);
  cv::Mat map_x(height, width, CV_32F), map_y(height, width, CV_32F), left_x(height, width, CV_32F);
  // Left pixel x sees texture column x + 100; right pixel xr sees the surface point whose left
  // column satisfies x - d(x) = xr, solved by fixed-point iteration (the plane is gentle).
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double d = d0 + a * x + b * y;
      pair.disparity.at<float>(y, x) = static_cast<float>(d);
      left_x.at<float>(y, x) = static_cast<float>(x + 100);
      double xl = x + d0;
      for (int it = 0; it < 20; ++it) xl = x + d0 + a * xl + b * y;
      map_x.at<float>(y, x) = static_cast<float>(xl + 100);
      map_y.at<float>(y, x) = static_cast<float>(y);
    }
  }
  cv::Mat left_f, right_f;
  cv::remap(texture, left_f, left_x, map_y, cv::INTER_CUBIC);
  cv::remap(texture, right_f, map_x, map_y, cv::INTER_CUBIC);
  left_f.convertTo(pair.left, CV_8U);
  right_f.convertTo(pair.right, CV_8U);
  return pair;
}

// A depth step: a textured box at disparity `near` over a background at `far` (two textures), so
// that the coarse neighbourhoods at its edges hold disparities further apart than one band. The
// right image shows the box where it covers the background; truth NaN where the left pixel is
// hidden in the right image.
constexpr int kBoxX0 = 100, kBoxX1 = 180, kBoxY0 = 40, kBoxY1 = 120;
SyntheticPair depthStep(int width, int height, int far, int near, uint32_t seed) {
  const cv::Mat background = randomTexture(width + 200, height, seed);
  const cv::Mat box = randomTexture(width + 200, height, seed + 1);
  auto inBox = [](int x, int y) { return x >= kBoxX0 && x < kBoxX1 && y >= kBoxY0 && y < kBoxY1; };
  SyntheticPair pair;
  pair.left.create(height, width, CV_8U);
  pair.right.create(height, width, CV_8U);
  pair.disparity.create(height, width, CV_32F);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const bool in = inBox(x, y);
      pair.left.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>((in ? box : background).at<float>(y, x + 100));
      const bool hidden = !in && inBox(x - far + near, y);  // the box covers its right pixel
      pair.disparity.at<float>(y, x) = hidden ? NAN : static_cast<float>(in ? near : far);
      const bool right_in = inBox(x + near, y);
      pair.right.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(right_in ? box.at<float>(y, x + near + 100)
                                                                         : background.at<float>(y, x + far + 100));
    }
  }
  return pair;
}

void expectBitIdentical(const DisparityMap& a, const DisparityMap& b, const std::string& what) {
  ASSERT_EQ(a.disparity.size(), b.disparity.size());
  // Premise: two empty maps, or two maps with no valid pixel, would be "identical" too.
  ASSERT_FALSE(a.disparity.empty()) << what;
  EXPECT_GT(cv::countNonZero(a.disparity < std::numeric_limits<float>::infinity()), 0) << what << ": no valid pixel";
  int mismatches = 0;
  for (int y = 0; y < a.disparity.rows; ++y) {
    for (int x = 0; x < a.disparity.cols; ++x) {
      const float da = a.disparity.at<float>(y, x), db = b.disparity.at<float>(y, x);
      const float ca = a.confidence.at<float>(y, x), cb = b.confidence.at<float>(y, x);
      const bool same = (da == db || (std::isinf(da) && std::isinf(db))) && ca == cb;
      if (!same && ++mismatches <= 5) {
        ADD_FAILURE() << what << ": pixel (" << x << ", " << y << "): disparity " << da << " vs " << db << ", confidence "
                      << ca << " vs " << cb;
      }
    }
  }
  EXPECT_EQ(mismatches, 0) << what;
}

cv::Mat greyCrop(const cv::Mat& bgr, const cv::Rect& roi) {
  cv::Mat grey;
  cv::cvtColor(bgr(roi), grey, cv::COLOR_BGR2GRAY);
  return grey;
}

struct ReferenceCase {
  const char* name;
  MatchingCost cost;
  int window, paths, min_disparity;
  bool adaptive, lr, naive_pkrn;
  Prefilter prefilter = Prefilter::kSobelX;
  SearchMode search = SearchMode::kFull;
  int disparities = 48;
  int coarse_scale = StereoConfig().coarse_scale;
  int p2 = -1;  // -1: the cost's default
};

class MatchesScalarReference : public ::testing::TestWithParam<ReferenceCase> {};

TEST_P(MatchesScalarReference, BitForBitWithOneStrip) {
  const ReferenceCase& rc = GetParam();
  cv::Mat left, right;
  if (auto cones = test::loadCones()) {
    left = greyCrop(cones->left, cv::Rect(150, 100, 120, 60));
    right = greyCrop(cones->right, cv::Rect(150, 100, 120, 60));
  } else {
    const SyntheticPair pair = slantedPlane(120, 60, 12.0, 0.02, 0.01, 3);
    left = pair.left;
    right = pair.right;
  }
  StereoConfig config;
  config.cost = rc.cost;
  config.window_px = rc.window;
  config.num_paths = rc.paths;
  config.num_disparities = rc.disparities;
  config.search = rc.search;
  config.coarse_scale = rc.coarse_scale;
  config.min_disparity_px = rc.min_disparity;
  config.adaptive_p2 = rc.adaptive;
  config.p2 = rc.p2;
  config.lr_check = rc.lr;
  config.pkrn_exclude_neighbours = !rc.naive_pkrn;
  config.prefilter = rc.prefilter;
  config.invalidate_truncated = rc.lr;  // exercised together with the LR check
  config.num_strips = 1;
  StereoMatcher matcher(config);
  expectBitIdentical(matcher.match(left, right), test::referenceSgm(left, right, config), rc.name);
}

INSTANTIATE_TEST_SUITE_P(
    Modes, MatchesScalarReference,
    ::testing::Values(ReferenceCase{"sad3_4paths", MatchingCost::kSad, 3, 4, 0, false, false, false},
                      ReferenceCase{"sad1_4paths", MatchingCost::kSad, 1, 4, 0, false, false, false},
                      ReferenceCase{"sad7_4paths_shifted", MatchingCost::kSad, 7, 4, 0, false, false, false},
                      ReferenceCase{"sad5_8paths", MatchingCost::kSad, 5, 8, 0, false, false, false},
                      ReferenceCase{"census5_4paths", MatchingCost::kCensus, 5, 4, 0, false, false, false},
                      ReferenceCase{"census3_8paths", MatchingCost::kCensus, 3, 8, 0, false, false, false},
                      ReferenceCase{"sad3_min_disparity", MatchingCost::kSad, 3, 4, 9, false, false, false},
                      ReferenceCase{"sad3_adaptive_p2", MatchingCost::kSad, 3, 4, 0, true, false, false},
                      ReferenceCase{"sad3_lr_check", MatchingCost::kSad, 3, 4, 0, false, true, false},
                      ReferenceCase{"sad3_8paths_lr_check", MatchingCost::kSad, 3, 8, 0, false, true, false},
                      ReferenceCase{"sad3_naive_pkrn", MatchingCost::kSad, 3, 4, 0, false, false, true},
                      ReferenceCase{"sad3_grey_levels", MatchingCost::kSad, 3, 4, 0, false, false, false, Prefilter::kNone},
                      ReferenceCase{"sad9_grey_levels_8paths", MatchingCost::kSad, 9, 8, 0, true, true, false,
                                    Prefilter::kNone},
                      // A full search of at most 32 disparities runs as one band that starts at 0
                      // (the coarse level's match): its lanes past the range hold sentinels.
                      ReferenceCase{"one_band_sad3_32_disparities_lr_check", MatchingCost::kSad, 3, 4, 0, false, true,
                                    false, Prefilter::kSobelX, SearchMode::kFull, 32},
                      ReferenceCase{"one_band_census5_16_disparities_8paths", MatchingCost::kCensus, 5, 8, 0, false, false,
                                    false, Prefilter::kSobelX, SearchMode::kFull, 16},
                      ReferenceCase{"one_band_sad5_16_disparities_adaptive_lr_min_disparity", MatchingCost::kSad, 5, 8, 9,
                                    true, true, false, Prefilter::kSobelX, SearchMode::kFull, 16},
                      // Coarse to fine: bands of 32 of the 48 (or 80) disparities.
                      ReferenceCase{"band_sad3_4paths", MatchingCost::kSad, 3, 4, 0, false, false, false,
                                    Prefilter::kSobelX, SearchMode::kBand},
                      ReferenceCase{"band_sad3_80_disparities", MatchingCost::kSad, 3, 4, 0, false, false, false,
                                    Prefilter::kSobelX, SearchMode::kBand, 80},
                      ReferenceCase{"band_sad3_half_size_coarse", MatchingCost::kSad, 3, 4, 0, false, false, false,
                                    Prefilter::kSobelX, SearchMode::kBand, 80, 2},
                      ReferenceCase{"band_sad3_half_size_coarse_min_disparity", MatchingCost::kSad, 3, 8, 9, false, true,
                                    false, Prefilter::kSobelX, SearchMode::kBand, 48, 2},
                      // Census bands run in byte lanes where the path costs fit a byte (the default
                      // penalties), in 16-bit lanes otherwise (P2 = 120).
                      ReferenceCase{"band_census5_4paths", MatchingCost::kCensus, 5, 4, 0, false, false, false,
                                    Prefilter::kSobelX, SearchMode::kBand},
                      ReferenceCase{"band_census3_8paths", MatchingCost::kCensus, 3, 8, 0, false, false, false,
                                    Prefilter::kSobelX, SearchMode::kBand},
                      ReferenceCase{"band_census5_adaptive_lr_min_disparity", MatchingCost::kCensus, 5, 4, 9, true, true,
                                    false, Prefilter::kSobelX, SearchMode::kBand, 80},
                      ReferenceCase{"band_census5_sixteen_bit_penalties", MatchingCost::kCensus, 5, 4, 0, false, true,
                                    false, Prefilter::kSobelX, SearchMode::kBand, 48, 4, 120},
                      ReferenceCase{"band_sad5_8paths", MatchingCost::kSad, 5, 8, 0, false, false, false,
                                    Prefilter::kSobelX, SearchMode::kBand},
                      ReferenceCase{"band_sad3_min_disparity", MatchingCost::kSad, 3, 4, 9, false, false, false,
                                    Prefilter::kSobelX, SearchMode::kBand},
                      ReferenceCase{"band_sad3_adaptive_lr_check", MatchingCost::kSad, 3, 4, 0, true, true, false,
                                    Prefilter::kSobelX, SearchMode::kBand},
                      ReferenceCase{"band_sad3_naive_pkrn_grey", MatchingCost::kSad, 3, 4, 0, false, false, true,
                                    Prefilter::kNone, SearchMode::kBand}),
    [](const ::testing::TestParamInfo<ReferenceCase>& info) { return std::string(info.param.name); });

// A census band runs in byte lanes where every value its recurrence forms fits a byte: census 5x5
// (sentinel 94 + P1 10, four paths' sum at most 216) and 3x3 at their default penalties, not with
// a larger P2 (sentinel 274), not where only the sum is too large (P2 50: 24 + 100 + 20 = 144, but
// 4 (24 + 50) = 296), never for SAD.
TEST(StereoMatcher, CensusBandsRunInBytesWhereTheirPathCostsFitAByte) {
  auto fits = [](MatchingCost cost, int window, int p2) {
    StereoConfig config;
    config.cost = cost;
    config.window_px = window;
    config.p2 = p2;
    return detail::bandFitsBytes(detail::paramsOf(config));
  };
  EXPECT_TRUE(fits(MatchingCost::kCensus, 5, -1));
  EXPECT_TRUE(fits(MatchingCost::kCensus, 3, -1));
  EXPECT_FALSE(fits(MatchingCost::kCensus, 5, 120));
  EXPECT_FALSE(fits(MatchingCost::kCensus, 5, 50));
  EXPECT_TRUE(fits(MatchingCost::kCensus, 5, 39));  // 4 (24 + 39) = 252
  EXPECT_FALSE(fits(MatchingCost::kSad, 3, -1));
}

// The band kernel holds one band in one vector on AVX-512 (and in bytes on AVX2) and in several on
// narrower instruction sets: every one of them the machine runs must match the reference, in
// 16-bit lanes (SAD, census with P2 = 120) and in bytes (census 5x5 and 3x3). Not HWY_SCALAR: the
// winner search needs at least 3 lanes per vector (see pickWinner()), in both search modes. The
// depth step's box edges exercise the bands placed at depth edges (band_placement.h).
TEST(StereoMatcher, BandMatchesTheReferenceOnEveryInstructionSet) {
  struct Variant {
    MatchingCost cost;
    int window, p2;
  };
  const Variant variants[] = {{MatchingCost::kSad, 3, -1},
                              {MatchingCost::kCensus, 5, -1},
                              {MatchingCost::kCensus, 3, -1},
                              {MatchingCost::kCensus, 5, 120}};
  const SyntheticPair plane = slantedPlane(120, 60, 20.0, 0.1, 0.05, 5);
  const SyntheticPair step = depthStep(200, 140, 6, 44, 9);
  for (const int64_t target : hwy::SupportedAndGeneratedTargets()) {
    if (target == HWY_SCALAR) continue;
    std::cout << "instruction set " << hwy::TargetName(target) << "\n";
    hwy::SetSupportedTargetsForTest(target);
    for (const Variant& variant : variants) {
      for (const SyntheticPair* scene : {&plane, &step}) {
        const SyntheticPair& pair = *scene;
        StereoConfig config;
        config.cost = variant.cost;
        config.window_px = variant.window;
        config.p2 = variant.p2;
        // The step with 112: its box's left edge (x = 100) lies in the columns invalidated as truncated.
        config.num_disparities = scene == &step ? 112 : 64;
        config.search = SearchMode::kBand;
        config.lr_check = true;
        config.num_strips = 1;
        StereoMatcher matcher(config);
        expectBitIdentical(matcher.match(pair.left, pair.right), test::referenceSgm(pair.left, pair.right, config),
                           std::string(hwy::TargetName(target)) + " " + toString(variant.cost) + " " +
                               std::to_string(variant.window) + " P2 " + std::to_string(variant.p2) +
                               (scene == &step ? " depth step" : " plane"));
      }
    }
  }
  hwy::SetSupportedTargetsForTest(0);
}

// At a depth step wider than one band, each pixel's band follows its own surface: near the box's
// edges the band search is as right as the full search (the coarse neighbourhood holds both
// disparities; the pixel's own coarse disparity is often the other surface's).
TEST(StereoMatcher, BandFollowsEachSurfaceAtADepthStep) {
  const SyntheticPair pair = depthStep(320, 200, 6, 44, 11);
  StereoConfig config;
  config.num_disparities = 64;
  config.lr_check = false;
  config.invalidate_truncated = false;
  auto wrongNearEdges = [&](SearchMode search) {
    config.search = search;
    const cv::Mat d = StereoMatcher(config).match(pair.left, pair.right).disparity;
    int wrong = 0, counted = 0;
    for (int y = kBoxY0 - 6; y < kBoxY1 + 6; ++y) {
      for (int x = kBoxX0 - 6; x < kBoxX1 + 6; ++x) {
        const bool near_edge = std::min({std::abs(x - kBoxX0), std::abs(x - kBoxX1), std::abs(y - kBoxY0),
                                         std::abs(y - kBoxY1)}) <= 6;
        const float truth = pair.disparity.at<float>(y, x);
        if (!near_edge || std::isnan(truth)) continue;
        ++counted;
        wrong += !(std::abs(d.at<float>(y, x) - truth) <= 1.0f);
      }
    }
    std::cout << "search " << toString(search) << ": " << wrong << " of " << counted
              << " pixels near the box's edges off by more than 1 px\n";
    return wrong;
  };
  const int full = wrongNearEdges(SearchMode::kFull);
  const int band = wrongNearEdges(SearchMode::kBand);
  EXPECT_LE(band, full);
}

TEST(StereoMatcher, OneAndTwoThreadsGiveBitIdenticalResults) {
  const SyntheticPair plane = slantedPlane(320, 240, 20.0, 0.03, 0.02, 7);
  const SyntheticPair step = depthStep(320, 240, 6, 44, 13);  // bands placed by the edge check too
  for (const SyntheticPair* scene : {&plane, &step}) {
    const SyntheticPair& pair = *scene;
    for (int paths : {4, 8}) {
      for (SearchMode search : {SearchMode::kFull, SearchMode::kBand}) {
        StereoConfig config;
        config.num_disparities = 64;
        config.num_paths = paths;
        config.search = search;
        config.lr_check = true;
        StereoMatcher matcher(config);
        const int saved = omp_get_max_threads();
        omp_set_num_threads(1);
        const DisparityMap one = matcher.match(pair.left, pair.right);
        omp_set_num_threads(2);
        const DisparityMap two = matcher.match(pair.left, pair.right);
        omp_set_num_threads(saved);
        expectBitIdentical(
            one, two,
            std::to_string(paths) + " paths, search " + toString(search) + (scene == &step ? ", depth step" : ", plane"));
      }
    }
  }
}

// A matcher writes a frame's result into the last frame's memory once the caller has released
// it, and never into a result the caller still holds.
TEST(StereoMatcher, RepeatedMatchesReuseOnlyReleasedMemory) {
  const SyntheticPair a = slantedPlane(200, 120, 15.0, 0.0, 0.0, 11);
  const SyntheticPair b = slantedPlane(200, 120, 9.0, 0.02, 0.01, 12);
  StereoConfig config;
  config.num_disparities = 32;
  StereoMatcher matcher(config), fresh(config);
  const DisparityMap expected_a = fresh.match(a.left, a.right);
  const DisparityMap expected_b = fresh.match(b.left, b.right);

  const DisparityMap held = matcher.match(a.left, a.right);
  const DisparityMap other = matcher.match(b.left, b.right);
  EXPECT_NE(other.disparity.ptr<float>(), held.disparity.ptr<float>());
  expectBitIdentical(held, expected_a, "result held while the next frame was matched");
  expectBitIdentical(other, expected_b, "next frame");

  DisparityMap released = matcher.match(a.left, a.right);
  const float* memory = released.disparity.ptr<float>();
  released = DisparityMap{};
  const DisparityMap reused = matcher.match(b.left, b.right);
  EXPECT_EQ(reused.disparity.ptr<float>(), memory);
  expectBitIdentical(reused, expected_b, "frame matched into released memory");
}

TEST(StereoMatcher, SubpixelErrorOnSlantedPlaneBelowFifteenHundredths) {
  const SyntheticPair pair = slantedPlane(400, 300, 18.0, 0.021, 0.013, 5);
  for (MatchingCost cost : {MatchingCost::kSad, MatchingCost::kCensus}) {
    StereoConfig config;
    config.cost = cost;
    config.window_px = cost == MatchingCost::kSad ? 3 : 5;
    config.num_disparities = 48;
    StereoMatcher matcher(config);
    const DisparityMap map = matcher.match(pair.left, pair.right);
    double sum = 0.0;
    int n = 0, invalid = 0;
    // Away from the borders, where the window and the search range are complete.
    for (int y = 10; y < 290; ++y) {
      for (int x = 60; x < 390; ++x) {
        const float d = map.disparity.at<float>(y, x);
        if (!std::isfinite(d)) {
          ++invalid;
          continue;
        }
        sum += std::abs(d - pair.disparity.at<float>(y, x));
        ++n;
      }
    }
    const double mae = sum / std::max(1, n);
    std::cout << toString(cost) << ": sub-pixel mean absolute error " << mae << " px over " << n << " pixels\n";
    EXPECT_LT(mae, 0.15) << toString(cost);
    EXPECT_EQ(invalid, 0);
  }
}

TEST(StereoMatcher, PixelsWithoutRightMatchAreInvalidNotZero) {
  const SyntheticPair pair = slantedPlane(100, 40, 10.0, 0.0, 0.0, 2);
  StereoConfig config;
  config.num_disparities = 16;
  config.min_disparity_px = 8;
  config.invalidate_truncated = false;  // the columns x < min_d only (the truncated ones: below),
  config.lr_check = false;              // and what the left image alone gives
  StereoMatcher matcher(config);
  const DisparityMap map = matcher.match(pair.left, pair.right);
  for (int y = 0; y < 40; ++y) {
    for (int x = 0; x < 8; ++x) {
      EXPECT_TRUE(std::isinf(map.disparity.at<float>(y, x))) << "(" << x << ", " << y << ")";
      EXPECT_EQ(map.confidence.at<float>(y, x), 0.0f);
    }
    EXPECT_TRUE(std::isfinite(map.disparity.at<float>(y, 8)));
  }
}

TEST(StereoMatcher, TruncatedSearchColumnsAreInvalidOnRequest) {
  const SyntheticPair pair = slantedPlane(100, 40, 10.0, 0.0, 0.0, 2);
  StereoConfig config;
  config.num_disparities = 16;
  config.min_disparity_px = 4;
  config.invalidate_truncated = true;
  const DisparityMap map = StereoMatcher(config).match(pair.left, pair.right);
  for (int y = 0; y < 40; ++y) {
    for (int x = 0; x < 4 + 16 - 1; ++x) EXPECT_TRUE(std::isinf(map.disparity.at<float>(y, x))) << x;
    EXPECT_TRUE(std::isfinite(map.disparity.at<float>(y, 4 + 16 - 1)));
  }
}

TEST(StereoMatcher, MinConfidenceInvalidatesExactlyThePixelsBelowIt) {
  SyntheticPair pair = slantedPlane(160, 100, 12.0, 0.0, 0.0, 4);
  pair.left(cv::Rect(60, 30, 50, 40)).setTo(cv::Scalar(128));  // a textureless patch: ambiguous
  pair.right(cv::Rect(48, 30, 50, 40)).setTo(cv::Scalar(128));
  StereoConfig config;
  config.num_disparities = 32;
  const DisparityMap all = StereoMatcher(config).match(pair.left, pair.right);
  config.min_confidence = 1.1;
  const DisparityMap kept = StereoMatcher(config).match(pair.left, pair.right);
  int removed = 0;
  for (int y = 0; y < 100; ++y) {
    for (int x = 0; x < 160; ++x) {
      const bool below = all.confidence.at<float>(y, x) < 1.1f;
      EXPECT_EQ(std::isinf(kept.disparity.at<float>(y, x)), below) << "(" << x << ", " << y << ")";
      removed += below;
    }
  }
  EXPECT_GT(removed, 0);
}

TEST(StereoMatcher, RejectsImagesOfDifferentSizes) {
  StereoMatcher matcher(StereoConfig{});
  const cv::Mat a(100, 200, CV_8U, cv::Scalar(0)), b(99, 200, CV_8U, cv::Scalar(0));
  EXPECT_EQ(cenote::test::errorMessage([&] { matcher.match(a, b); }), "stereo: right image is 200x99 but left is 200x100");
}

TEST(StereoMatcher, RejectsEmptyAndNonEightBitImages) {
  StereoMatcher matcher(StereoConfig{});
  EXPECT_THROW(matcher.match(cv::Mat(), cv::Mat(10, 10, CV_8U)), Error);
  EXPECT_THROW(matcher.match(cv::Mat(10, 10, CV_16U), cv::Mat(10, 10, CV_16U)), Error);
}

TEST(StereoMatcher, ImagesNarrowerThanTheSearchRangeGiveInvalidPixelsNotACrash) {
  const cv::Mat a(5, 7, CV_8U, cv::Scalar(9)), b(5, 7, CV_8U, cv::Scalar(9));
  StereoConfig config;
  config.num_disparities = 64;
  config.min_disparity_px = 10;
  StereoMatcher matcher(config);
  const DisparityMap map = matcher.match(a, b);
  EXPECT_EQ(cv::countNonZero(map.confidence > 0.0f), 0);
}

TEST(DisparityToDepth, FocalTimesBaselineOverDisparityAndInfinityWhereInvalid) {
  cv::Mat d = (cv::Mat_<float>(1, 4) << 10.0f, 0.0f, std::numeric_limits<float>::infinity(), 2.5f);
  const cv::Mat z = disparityToDepth(d, 500.0, 0.1);
  EXPECT_FLOAT_EQ(z.at<float>(0, 0), 5.0f);
  EXPECT_TRUE(std::isinf(z.at<float>(0, 1)));
  EXPECT_TRUE(std::isinf(z.at<float>(0, 2)));
  EXPECT_FLOAT_EQ(z.at<float>(0, 3), 20.0f);
}

}  // namespace
}  // namespace cenote::pipeline
