// Accuracy of the stereo engine on real Middlebury pairs with ground truth (skipped when the
// data is absent). Numbers are printed so that a failing threshold shows how far off it is.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <sstream>
#include <vector>

#include "pipeline/stereo/stereo_matcher.h"
#include "tests/support/test_data.h"

namespace cenote::pipeline {
namespace {

using test::BadPixelStats;
using test::StereoPairWithTruth;

StereoConfig configFor(const StereoPairWithTruth& pair, MatchingCost cost, int window, int paths,
                       SearchMode search = StereoConfig().search) {
  StereoConfig c;
  // The matcher alone, as Middlebury's tables and OpenCV's SGBM score it (an invalid pixel counts
  // as bad): without the mapping filters that the defaults switch on.
  c.lr_check = false;
  c.invalidate_truncated = false;
  c.search = search;
  c.num_disparities = pair.num_disparities;
  c.cost = cost;
  c.window_px = window;
  c.num_paths = paths;
  return c;
}

BadPixelStats evaluate(const StereoPairWithTruth& pair, const StereoConfig& config, DisparityMap* out = nullptr) {
  StereoMatcher matcher(config);
  DisparityMap map = matcher.match(pair.left, pair.right);
  const BadPixelStats s = test::badPixels(map.disparity, pair);
  std::cout << pair.name << " " << toString(config.cost) << " " << config.window_px << "x" << config.window_px << " "
            << config.num_paths << " paths, search " << toString(config.search)
            << (config.usesBand() ? " coarse_scale " + std::to_string(config.coarse_scale) : std::string()) << ": bad-1 "
            << s.bad1 << " %, bad-2 " << s.bad2 << " %, density " << s.density << " %\n";
  if (out) *out = std::move(map);
  return s;
}

// The matches of SAD 3x3 on 4 paths with the setting `flag` off, then on.
std::pair<DisparityMap, DisparityMap> matchesWithoutAndWith(const StereoPairWithTruth& pair, bool StereoConfig::*flag) {
  StereoConfig config = configFor(pair, MatchingCost::kSad, 3, 4);
  std::pair<DisparityMap, DisparityMap> maps;
  config.*flag = false;
  evaluate(pair, config, &maps.first);
  config.*flag = true;
  evaluate(pair, config, &maps.second);
  return maps;
}

// OpenCV's StereoSGBM with the same window, disparities and penalties; its disparities are
// fixed point (x16) and invalid below minDisparity.
BadPixelStats evaluateOpenCv(const StereoPairWithTruth& pair, const StereoConfig& config, int mode) {
  auto sgbm = cv::StereoSGBM::create(0, config.num_disparities, config.window_px, config.effectiveP1(),
                                     config.effectiveP2(), -1, 0, 0, 0, 0, mode);
  cv::Mat left, right, fixed;
  cv::cvtColor(pair.left, left, cv::COLOR_BGR2GRAY);
  cv::cvtColor(pair.right, right, cv::COLOR_BGR2GRAY);
  sgbm->compute(left, right, fixed);
  cv::Mat disparity(fixed.size(), CV_32F);
  for (int y = 0; y < fixed.rows; ++y) {
    for (int x = 0; x < fixed.cols; ++x) {
      const int16_t v = fixed.at<int16_t>(y, x);
      disparity.at<float>(y, x) = v < 0 ? INFINITY : v / 16.0f;
    }
  }
  const BadPixelStats s = test::badPixels(disparity, pair);
  std::cout << pair.name << " OpenCV StereoSGBM mode " << mode << ": bad-1 " << s.bad1 << " %, bad-2 " << s.bad2
            << " %, density " << s.density << " %\n";
  return s;
}

// SAD 3x3 on 4 paths, band (the default) and full search: bad-2 no worse than the better of
// OpenCV's SGBM modes (HH4, 3-way) with the band's settings.
void expectBad2NoWorseThanOpenCvSgbm(const StereoPairWithTruth& pair) {
  const StereoConfig band = configFor(pair, MatchingCost::kSad, 3, 4, SearchMode::kBand);
  const double opencv = std::min(evaluateOpenCv(pair, band, cv::StereoSGBM::MODE_HH4).bad2,
                                 evaluateOpenCv(pair, band, cv::StereoSGBM::MODE_SGBM_3WAY).bad2);
  EXPECT_LE(evaluate(pair, band).bad2, opencv);
  EXPECT_LE(evaluate(pair, configFor(pair, MatchingCost::kSad, 3, 4, SearchMode::kFull)).bad2, opencv);
}

#define REQUIRE_PAIR(var, loader) \
  auto var = loader();            \
  if (!var) GTEST_SKIP() << "test data absent (" #loader ")";

TEST(MiddleburyCones, SadThreeByThreeFourPathsBad1AtMostTenPercent) {
  REQUIRE_PAIR(pair, test::loadCones);
  EXPECT_LE(evaluate(*pair, configFor(*pair, MatchingCost::kSad, 3, 4)).bad1, 10.0);
}

// The paper's cost exactly: SAD of grey levels.
TEST(MiddleburyCones, SadOfGreyLevelsFourPathsBad1AtMostTenPercent) {
  REQUIRE_PAIR(pair, test::loadCones);
  StereoConfig config = configFor(*pair, MatchingCost::kSad, 3, 4);
  config.prefilter = Prefilter::kNone;
  EXPECT_LE(evaluate(*pair, config).bad1, 10.0);
}

TEST(MiddleburyCones, CensusFiveByFiveFourPathsBad1AtMostFiveAndHalfPercent) {
  REQUIRE_PAIR(pair, test::loadCones);
  EXPECT_LE(evaluate(*pair, configFor(*pair, MatchingCost::kCensus, 5, 4)).bad1, 5.5);
}

TEST(MiddleburyCones, EightPathsNoWorseThanFour) {
  REQUIRE_PAIR(pair, test::loadCones);
  const double four = evaluate(*pair, configFor(*pair, MatchingCost::kSad, 3, 4)).bad1;
  const double eight = evaluate(*pair, configFor(*pair, MatchingCost::kSad, 3, 8)).bad1;
  EXPECT_LE(eight, four);
}

TEST(MiddleburyCones, LeftRightCheckRemovesMoreBadThanGoodPixels) {
  REQUIRE_PAIR(pair, test::loadCones);
  const auto [plain, checked] = matchesWithoutAndWith(*pair, &StereoConfig::lr_check);
  int removed_bad = 0, removed_good = 0;
  for (int y = 0; y < pair->mask.rows; ++y) {
    for (int x = 0; x < pair->mask.cols; ++x) {
      if (!pair->mask.at<uint8_t>(y, x)) continue;
      if (std::isfinite(plain.disparity.at<float>(y, x)) && !std::isfinite(checked.disparity.at<float>(y, x))) {
        const bool bad = std::abs(plain.disparity.at<float>(y, x) - pair->truth.at<float>(y, x)) > 1.0f;
        (bad ? removed_bad : removed_good)++;
      }
    }
  }
  std::cout << "LR check removed " << removed_bad << " bad and " << removed_good << " good pixels\n";
  EXPECT_GT(removed_bad, 0);
  EXPECT_GT(removed_bad, removed_good);
}

// bad-1 among the `fraction` most confident evaluated pixels.
double bad1OfMostConfident(const StereoPairWithTruth& pair, const DisparityMap& map, double fraction) {
  std::vector<std::pair<float, bool>> pixels;  // (confidence, bad)
  for (int y = 0; y < pair.mask.rows; ++y) {
    for (int x = 0; x < pair.mask.cols; ++x) {
      if (!pair.mask.at<uint8_t>(y, x)) continue;
      const float d = map.disparity.at<float>(y, x);
      const bool bad = !std::isfinite(d) || std::abs(d - pair.truth.at<float>(y, x)) > 1.0f;
      pixels.push_back({map.confidence.at<float>(y, x), bad});
    }
  }
  std::stable_sort(pixels.begin(), pixels.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  const size_t n = static_cast<size_t>(fraction * pixels.size());
  size_t bad = 0;
  for (size_t i = 0; i < n; ++i) bad += pixels[i].second;
  return 100.0 * bad / std::max<size_t>(1, n);
}

TEST(MiddleburyCones, MostConfidentFifthHasAtMostAThirdOfOverallBad1) {
  REQUIRE_PAIR(pair, test::loadCones);
  const StereoConfig config = configFor(*pair, MatchingCost::kSad, 3, 4);
  DisparityMap map;
  const double overall = evaluate(*pair, config, &map).bad1;
  const double top = bad1OfMostConfident(*pair, map, 0.2);
  std::cout << "PKRN (neighbours excluded): bad-1 of the 20 % most confident " << top << " % vs " << overall
            << " % overall\n";
  EXPECT_LE(top, overall / 3.0);
}

// Area under the sparsification curve (Hu & Mordohai 2012): mean bad-1 of the most confident
// 5 %, 10 %, ..., 100 % of the pixels. A confidence that ranks errors last has the smaller area.
double sparsificationArea(const StereoPairWithTruth& pair, const DisparityMap& map) {
  double area = 0.0;
  for (int step = 1; step <= 20; ++step) area += bad1OfMostConfident(pair, map, step / 20.0);
  return area / 20.0;
}

// The reason for excluding d*-1..d*+1 from the second minimum: measured, not assumed.
TEST(MiddleburyCones, PkrnExcludingNeighboursRanksBetterThanNaiveSecondMinimum) {
  REQUIRE_PAIR(pair, test::loadCones);
  const auto [naive, excluded] = matchesWithoutAndWith(*pair, &StereoConfig::pkrn_exclude_neighbours);
  const double e = sparsificationArea(*pair, excluded), n = sparsificationArea(*pair, naive);
  std::cout << "PKRN sparsification area (mean bad-1 over 5..100 % most confident): " << e << " % excluding neighbours vs "
            << n << " % naive\n";
  EXPECT_LT(e, n);
}

TEST(MiddleburyCloth3, Bad2NoWorseThanOpenCvSgbm) {
  REQUIRE_PAIR(pair, test::loadCloth3);
  expectBad2NoWorseThanOpenCvSgbm(*pair);
}

TEST(MiddleburyMotorcycle, Bad2NoWorseThanOpenCvSgbm) {
  REQUIRE_PAIR(pair, test::loadMotorcycle);
  expectBad2NoWorseThanOpenCvSgbm(*pair);
}

// Coarse to fine (SearchMode::kBand) against the same thresholds as the full search, whichever
// of the two is the default.
TEST(MiddleburyCones, BandSearchMeetsTheFullSearchThresholds) {
  REQUIRE_PAIR(pair, test::loadCones);
  EXPECT_LE(evaluate(*pair, configFor(*pair, MatchingCost::kSad, 3, 4, SearchMode::kBand)).bad1, 10.0);
  EXPECT_LE(evaluate(*pair, configFor(*pair, MatchingCost::kCensus, 5, 4, SearchMode::kBand)).bad1, 5.5);
  EXPECT_LE(evaluate(*pair, configFor(*pair, MatchingCost::kSad, 3, 4, SearchMode::kFull)).bad1, 10.0);
  EXPECT_LE(evaluate(*pair, configFor(*pair, MatchingCost::kCensus, 5, 4, SearchMode::kFull)).bad1, 5.5);
  // The other coarse scale (the default is 4: quarter size).
  for (const MatchingCost cost : {MatchingCost::kSad, MatchingCost::kCensus}) {
    StereoConfig half = configFor(*pair, cost, cost == MatchingCost::kSad ? 3 : 5, 4, SearchMode::kBand);
    half.coarse_scale = 2;
    EXPECT_LE(evaluate(*pair, half).bad1, cost == MatchingCost::kSad ? 10.0 : 5.5);
  }
}

// Band against full search on every real pair, SAD 3x3 on 4 paths (the defaults), as a table.
// Target: band bad-2 within 0.5 points of full search, with the default quarter-size coarse level
// and with the half-size one (coarse_scale 2). The edge check of band_placement.h is what brings
// the quarter size there on Motorcycle and Aloe (0.83 and 1.56 points above full search without it).
TEST(MiddleburyPairs, BandSearchBad2NearFullSearch) {
  const auto loads = {test::loadCones, test::loadCloth3, test::loadMotorcycle, test::loadAloe};
  std::ostringstream table;
  table << "| pair | full bad-2 % | band (coarse 1/4) | band (coarse 1/2) |\n|---|---|---|---|\n";
  int pairs = 0;
  for (const auto load : loads) {
    const auto pair = load();
    if (!pair) continue;
    ++pairs;
    const double full = evaluate(*pair, configFor(*pair, MatchingCost::kSad, 3, 4, SearchMode::kFull)).bad2;
    StereoConfig band = configFor(*pair, MatchingCost::kSad, 3, 4, SearchMode::kBand);
    const double quarter = evaluate(*pair, band).bad2;
    band.coarse_scale = 2;
    const double half = evaluate(*pair, band).bad2;
    table << "| " << pair->name << " | " << full << " | " << quarter << " | " << half << " |\n";
    EXPECT_LE(quarter, full + 0.5) << pair->name;
    EXPECT_LE(half, full + 0.5) << pair->name;
  }
  std::cout << table.str();
  if (pairs == 0) GTEST_SKIP() << "test data absent (no Middlebury pair)";
}

}  // namespace
}  // namespace cenote::pipeline
