#include "pipeline/stereo/stereo_config.h"

#include <gtest/gtest.h>

#include "common/error.h"
#include "common/yaml_section.h"
#include "tests/support/error_message.h"

namespace cenote::pipeline {
namespace {

std::string errorsOf(const StereoConfig& config) { return formatConfigErrors(config.validate()); }

TEST(StereoConfig, DefaultsAreValid) {
  EXPECT_EQ(errorsOf(StereoConfig{}), "");
  EXPECT_EQ(errorsOf({.cost = MatchingCost::kCensus, .window_px = 5}), "");
  EXPECT_EQ(errorsOf({.num_paths = 8}), "");
}

TEST(StereoConfig, RejectsDisparitiesNotMultipleOf16) {
  EXPECT_EQ(errorsOf({.num_disparities = 100}), "stereo.num_disparities = 100: must be a multiple of 16 in [16, 512]");
}

TEST(StereoConfig, RejectsEvenSadWindowAndCensusWindowOtherThanThreeOrFive) {
  EXPECT_EQ(errorsOf({.window_px = 4}), "stereo.window_px = 4: SAD window must be odd in [1, 9]");
  EXPECT_EQ(errorsOf({.cost = MatchingCost::kCensus, .window_px = 7}),
            "stereo.window_px = 7: census window must be 3 or 5");
}

TEST(StereoConfig, ReportsEveryFailedRuleNotJustTheFirst) {
  const StereoConfig c{.min_disparity_px = -3, .num_paths = 6, .num_strips = 0};
  EXPECT_EQ(c.validate().size(), 3u) << errorsOf(c);
}

TEST(StereoConfig, RejectsPenaltiesThatWouldOverflowSixteenBitSums) {
  const StereoConfig c{.num_paths = 8, .p1 = 100, .p2 = 9000};
  EXPECT_NE(errorsOf(c).find("stereo.p2 = 9000: num_paths * (max cost"), std::string::npos) << errorsOf(c);
}

TEST(StereoConfig, RejectsP2BelowP1) { EXPECT_EQ(errorsOf({.p1 = 50, .p2 = 20}), "stereo.p2 = 20: must be >= p1 (50)"); }

TEST(StereoConfig, SadCostRangeFollowsWindowAndPrefilter) {
  StereoConfig c;
  c.prefilter = Prefilter::kNone;
  EXPECT_EQ(c.maxCost(), 9 * 255);
  EXPECT_EQ(c.sadShift(), 0);
  c.window_px = 9;
  EXPECT_EQ(c.sadShift(), 3);  // 81 * 255 = 20655 >> 3 = 2581 <= 4095
  c.prefilter = Prefilter::kSobelX;
  c.window_px = 3;
  EXPECT_EQ(c.maxCost(), 9 * 126);
}

TEST(StereoConfig, ReadsYamlAndRejectsUnknownCostName) {
  YamlSection ok(YAML::Load("{cost: census, window_px: 3, num_paths: 8, lr_check: true}"), "stereo", "c.yaml");
  StereoConfig c;
  c.read(ok);
  ok.finish();
  EXPECT_EQ(c.cost, MatchingCost::kCensus);
  EXPECT_EQ(c.window_px, 3);
  EXPECT_EQ(c.num_paths, 8);
  EXPECT_TRUE(c.lr_check);
  YamlSection bad(YAML::Load("{cost: ncc}"), "stereo", "c.yaml");
  EXPECT_EQ(cenote::test::errorMessage([&] { c.read(bad); }), "stereo.cost = ncc: must be 'sad' or 'census'");
}

TEST(StereoConfig, ReadsSearchModeAndRejectsUnknownName) {
  YamlSection ok(YAML::Load("{search: band}"), "stereo", "c.yaml");
  StereoConfig c;
  c.search = SearchMode::kFull;
  c.read(ok);
  ok.finish();
  EXPECT_EQ(c.search, SearchMode::kBand);
  EXPECT_TRUE(c.usesBand());
  c.num_disparities = kBandDisparities;  // a range no wider than the band is searched in full
  EXPECT_FALSE(c.usesBand());
  YamlSection bad(YAML::Load("{search: coarse}"), "stereo", "c.yaml");
  EXPECT_EQ(cenote::test::errorMessage([&] { c.read(bad); }), "stereo.search = coarse: must be 'full' or 'band'");
}

TEST(StereoConfig, CoarseScaleIsTwoOrFourAndShrinksTheRangeOutwards) {
  YamlSection yaml(YAML::Load("{coarse_scale: 2}"), "stereo", "c.yaml");
  StereoConfig c;
  c.read(yaml);
  yaml.finish();
  EXPECT_EQ(c.coarse_scale, 2);
  c.coarse_scale = 3;
  EXPECT_EQ(errorsOf(c), "stereo.coarse_scale = 3: must be 2 or 4");
  c.coarse_scale = 4;
  c.min_disparity_px = 9;
  c.num_disparities = 112;  // [9, 121) -> [2, 31)
  const StereoConfig coarse = c.coarseConfig();
  EXPECT_EQ(coarse.min_disparity_px, 2);
  EXPECT_EQ(coarse.num_disparities, 29);
  EXPECT_EQ(coarse.search, SearchMode::kFull);
  ASSERT_EQ(c.maxCost(), 1134);    // 9 * 126: SAD 3x3 of the clipped derivative
  EXPECT_EQ(coarse.num_paths, 8);  // 8 * (1134 + 90 + 720) fits 16 bits
  c.p2 = 8000;                     // 4 * (1134 + 90 + 8000) fits, 8 * does not: the configured 4 paths
  EXPECT_TRUE(c.validate().empty());
  EXPECT_EQ(c.coarseConfig().num_paths, 4);
  c.p2 = -1;
  // Band centred on 4 * 20 = 80, i.e. index 71: starts 16 lower; none: 0; cut by the border.
  EXPECT_EQ(c.bandStart(20.0f, 400), 55);
  EXPECT_EQ(c.bandStart(INFINITY, 400), 0);
  EXPECT_EQ(c.bandStart(20.0f, 50), 50 - 9 + 1 - kBandDisparities);
  EXPECT_EQ(c.bandStartAround(82, 400), 82 - 9 - kBandDisparities / 2);
  EXPECT_EQ(c.bandStartAround(0, 400), 0);
}

TEST(StereoConfig, ConstructingAMatcherWithAnInvalidConfigThrowsWithEveryRule) {
  StereoConfig c;
  c.num_disparities = 7;
  c.window_px = 2;
  EXPECT_THROW(
      {
        try {
          throwIfInvalid(c.validate(), "stereo configuration");
        } catch (const Error& e) {
          EXPECT_NE(std::string(e.what()).find("stereo.num_disparities = 7"), std::string::npos);
          EXPECT_NE(std::string(e.what()).find("stereo.window_px = 2"), std::string::npos);
          throw;
        }
      },
      Error);
}

}  // namespace
}  // namespace cenote::pipeline
