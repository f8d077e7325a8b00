#include "pipeline/fusion/fusion_config.h"

#include <gtest/gtest.h>

#include <cmath>

#include "common/error.h"
#include "common/yaml_section.h"
#include "tests/support/config_defaults.h"

namespace cenote::pipeline {
namespace {

// The one error of a config with one bad rule, as text.
std::string onlyError(const FusionConfig& config) {
  const auto errors = config.validate();
  if (errors.size() != 1) return std::to_string(errors.size()) + " errors";
  return errors[0].toString();
}

TEST(FusionConfig, DefaultsAreValid) {
  EXPECT_TRUE(FusionConfig{}.validate().empty());
  const FusionConfig c;
  EXPECT_EQ(c.num_views, 3);
  EXPECT_EQ(c.eps, 0.04);
  EXPECT_EQ(c.support_radius, SupportRadius::kRelative);
  EXPECT_EQ(c.min_fused_confidence, 0.5);
}

TEST(FusionConfig, RejectsEvenOrTooFewOrTooManyViews) {
  for (int n : {1, 2, 4, 17}) {
    FusionConfig c;
    c.num_views = n;
    EXPECT_EQ(onlyError(c),
              "fusion.num_views = " + std::to_string(n) + ": must be odd in [3, 15] (the middle view is the reference)");
  }
  FusionConfig c;
  c.num_views = 15;
  EXPECT_TRUE(c.validate().empty());
}

TEST(FusionConfig, RejectsRelativeEpsOutsideZeroOne) {
  EXPECT_EQ(onlyError({.eps = 1.5}), "fusion.eps = 1.5: relative support radius must be in (0, 1) (a fraction of depth)");
  EXPECT_EQ(FusionConfig{.eps = 0.0}.validate().size(), 1u);
}

TEST(FusionConfig, AcceptsAbsoluteEpsInMetresAboveOne) {
  FusionConfig c;
  c.support_radius = SupportRadius::kAbsolute;
  c.eps = 1.5;
  EXPECT_TRUE(c.validate().empty());
  c.eps = -0.1;
  EXPECT_EQ(onlyError(c), "fusion.eps = -0.1: absolute support radius must be > 0 metres and finite");
}

TEST(FusionConfig, RejectsNonPositiveFusedThreshold) {
  EXPECT_EQ(onlyError({.min_fused_confidence = 0.0}), "fusion.min_fused_confidence = 0: must be > 0 and finite");
}

TEST(FusionConfig, RejectsNegativeInputFloor) {
  EXPECT_EQ(onlyError({.min_input_confidence = -1.0}), "fusion.min_input_confidence = -1: must be >= 0 and finite");
}

TEST(FusionConfig, RejectsNonPositiveMaxDepth) {
  EXPECT_EQ(onlyError({.max_depth_m = 0.0}), "fusion.max_depth_m = 0: must be > 0 (.inf for no limit)");
  EXPECT_EQ(FusionConfig{.max_depth_m = NAN}.validate().size(), 1u);
}

TEST(FusionConfig, ReportsEveryFailedRule) {
  const FusionConfig c{.num_views = 2, .eps = 2.0, .min_fused_confidence = -1.0, .max_depth_m = -3.0};
  EXPECT_EQ(c.validate().size(), 4u);
}

TEST(FusionConfig, ReadsYamlAndRejectsUnknownKeys) {
  const YAML::Node root = YAML::Load(
      "fusion:\n  num_views: 5\n  eps: 0.05\n  support_radius: absolute\n  min_fused_confidence: 1.5\n"
      "  min_input_confidence: 1.1\n  max_depth_m: 12.0\n");
  YamlSection section(root["fusion"], "fusion", "test.yaml");
  FusionConfig c;
  c.read(section);
  section.finish();
  EXPECT_EQ(c.num_views, 5);
  EXPECT_EQ(c.eps, 0.05);
  EXPECT_EQ(c.support_radius, SupportRadius::kAbsolute);
  EXPECT_EQ(c.min_fused_confidence, 1.5);
  EXPECT_EQ(c.min_input_confidence, 1.1);
  EXPECT_EQ(c.max_depth_m, 12.0);

  const YAML::Node typo = YAML::Load("fusion:\n  num_veiws: 5\n");
  YamlSection bad(typo["fusion"], "fusion", "test.yaml");
  FusionConfig d;
  d.read(bad);
  EXPECT_THROW(bad.finish(), Error);
  EXPECT_THROW(parseSupportRadius("percent"), Error);
}

// The paper's rules keep their defaults in config/default.yaml; the one deliberate difference is
// the working range: the library takes every depth, the mapping pipeline stops where stereo depth
// error passes 5 cm for the simulator's rig (see the comment in config/default.yaml).
TEST(FusionConfig, DefaultYamlSectionIsValidAndMatchesTheDefaults) {
  const std::string path = std::string(CENOTE_SOURCE_DIR) + "/config/default.yaml";
  FusionConfig c;
  readConfigFile(path, "fusion", c);
  EXPECT_TRUE(c.validate().empty());
  YamlDefaults defaults;
  test::recordSectionDefaults<FusionConfig>(defaults, "fusion");
  ASSERT_GE(defaults.entries.size(), 6u);  // num_views, eps, support_radius, the confidences, max_depth_m
  test::expectFileHoldsDefaults(loadYamlFile(path), path, defaults);
  EXPECT_EQ(FusionConfig().max_depth_m, 4.0);
}

}  // namespace
}  // namespace cenote::pipeline
