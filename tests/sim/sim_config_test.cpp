#include "sim/sim_config.h"

#include <gtest/gtest.h>

#include "common/error.h"
#include "common/yaml_section.h"
#include "tests/support/config_defaults.h"
#include "tests/support/error_message.h"

namespace cenote::sim {
namespace {

std::string errorsOf(const SimConfig& config) { return formatConfigErrors(config.validate()); }

TEST(SimConfig, DefaultsAreValid) { EXPECT_EQ(errorsOf(SimConfig{}), ""); }

TEST(SimConfig, ReportsEveryFailedRuleWithKeyAndValue) {
  SimConfig c;
  c.num_frames = 0;
  c.baseline_m = -0.1;
  c.groundtruth_rate_hz = 10.0;  // below the camera rate
  const std::string text = errorsOf(c);
  EXPECT_NE(text.find("sim.num_frames = 0: must be in [1, 100000]"), std::string::npos) << text;
  EXPECT_NE(text.find("sim.baseline_m = -0.1: must be in (0, 2]"), std::string::npos) << text;
  EXPECT_NE(text.find("sim.groundtruth_rate_hz = 10: must be in [rate_hz, 10000]"), std::string::npos) << text;
}

TEST(SimConfig, ReadsSectionAndRejectsUnknownKey) {
  SimConfig c;
  YamlSection root(YAML::Load("sim: {scene: wreck, num_frames: 7, noise_sigma: 0.5}"), "", "test.yaml");
  root.readSection("sim", c);
  EXPECT_EQ(c.scene, SimSceneKind::kWreck);
  EXPECT_EQ(c.num_frames, 7);
  EXPECT_DOUBLE_EQ(c.noise_sigma, 0.5);

  YamlSection bad_root(YAML::Load("sim: {num_frame: 7}"), "", "test.yaml");
  YamlSection bad = bad_root.section("sim");
  SimConfig d;
  d.read(bad);
  EXPECT_THROW(bad.finish(), Error);
}

TEST(SimConfig, DefaultYamlSectionReadsAndEqualsTheDefaults) {
  const std::string path = std::string(CENOTE_SOURCE_DIR) + "/config/default.yaml";
  SimConfig c;
  readConfigFile(path, "sim", c);
  EXPECT_EQ(errorsOf(c), "");
  YamlDefaults defaults;
  test::recordSectionDefaults<SimConfig>(defaults, "sim");
  ASSERT_GE(defaults.entries.size(), 5u);  // scene, num_frames, baseline_m, mesh_spacing_m, surface_spacing_m, ...
  test::expectFileHoldsDefaults(loadYamlFile(path), path, defaults);
}

TEST(SimConfig, UnknownSceneNameIsAnError) {
  EXPECT_EQ(parseSimScene("reef"), SimSceneKind::kReef);
  EXPECT_EQ(cenote::test::errorMessage([&] { parseSimScene("ocean"); }),
            "sim.scene = ocean: must be 'cave', 'reef' or 'wreck'");
}

}  // namespace
}  // namespace cenote::sim
