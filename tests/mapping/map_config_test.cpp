#include "mapping/map_config.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "common/error.h"
#include "common/yaml_section.h"

namespace cenote::mapping {
namespace {

std::string errorsOf(const MapConfig& config) { return formatConfigErrors(config.validate()); }

TEST(MapConfig, DefaultsAreValid) { EXPECT_EQ(errorsOf(MapConfig{}), ""); }

TEST(MapConfig, DefaultSensorModelIsOctoMaps) {
  const LogOddsModel model = MapConfig{}.logOddsModel();
  EXPECT_NEAR(model.hit, 0.8473, 1e-4);
  EXPECT_NEAR(model.miss, -0.4055, 1e-4);
  EXPECT_NEAR(model.clamp_min, -1.9924, 1e-4);
  EXPECT_NEAR(model.clamp_max, 3.4761, 1e-4);
  EXPECT_EQ(model.occupied, 0.0f);
}

TEST(MapConfig, RejectsAbsurdResolutions) {
  for (double s : {0.0, -0.05, 1e-6, 1e9, std::numeric_limits<double>::quiet_NaN()}) {
    MapConfig c;
    c.voxel_size_m = s;
    EXPECT_NE(errorsOf(c).find("map.voxel_size_m"), std::string::npos) << "voxel_size_m " << s;
  }
}

TEST(MapConfig, ReportsEveryFailedRuleNotJustTheFirst) {
  MapConfig c;
  c.prob_hit = 0.4;
  c.prob_miss = 0.6;
  c.frontier_min_voxels = 0;
  const auto errors = c.validate();
  ASSERT_GE(errors.size(), 3u);
  EXPECT_EQ(errors[0].toString(), "map.prob_hit = 0.4: must be in (0.5, 1)");
  EXPECT_EQ(errors[1].toString(), "map.prob_miss = 0.6: must be in (0, 0.5)");
}

TEST(MapConfig, ReadsCorrectionMoveAndRejectsAnUnknownOneNamingTheNamesAllowed) {
  EXPECT_EQ(MapConfig{}.correction_move, CorrectionMove::kMarch);
  const YAML::Node node = YAML::Load("correction_move: resample\n");
  MapConfig c;
  YamlSection section(node, "map", "test.yaml");
  c.read(section);
  section.finish();
  EXPECT_EQ(c.correction_move, CorrectionMove::kResample);

  const YAML::Node bad = YAML::Load("correction_move: rewind\n");
  YamlSection bad_section(bad, "map", "test.yaml");
  MapConfig d;
  try {
    d.read(bad_section);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "map.correction_move = rewind: must be 'march' or 'resample'");
  }
}

TEST(MapConfig, ReadsKeysAndRejectsUnknownOnes) {
  const YAML::Node node = YAML::Load("voxel_size_m: 0.1\nmax_range_m: 5\n");
  MapConfig c;
  YamlSection section(node, "map", "test.yaml");
  c.read(section);
  section.finish();
  EXPECT_EQ(c.voxel_size_m, 0.1);
  EXPECT_EQ(c.max_range_m, 5.0);

  const YAML::Node typo = YAML::Load("voxel_sise: 0.1\n");
  YamlSection bad(typo, "map", "test.yaml");
  MapConfig d;
  d.read(bad);
  EXPECT_THROW(bad.finish(), Error);
}

TEST(MapConfig, DefaultYamlSectionIsValid) {
  const YAML::Node root = loadYamlFile(std::string(CENOTE_SOURCE_DIR) + "/config/default.yaml");
  MapConfig c;
  YamlSection section(root["map"], "map", "default.yaml");
  c.read(section);
  section.finish();
  EXPECT_EQ(errorsOf(c), "");
  EXPECT_EQ(c.voxel_size_m, 0.05);
}

}  // namespace
}  // namespace cenote::mapping
