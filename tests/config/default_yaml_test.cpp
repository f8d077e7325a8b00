// config/default.yaml against the code's defaults: the file documents the defaults, the structs
// define them (a run without --config uses the structs), and the two must be the same value for
// every key of every section. The keys come from the config structs' own read() functions
// (YamlSection::recordDefaults), so a key added later is checked without touching this test.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "common/yaml_section.h"
#include "mapping/map_config.h"
#include "pipeline/dataset/recording_config.h"
#include "pipeline/runner/run_config.h"
#include "server/server_config.h"
#include "sim/sim_config.h"
#include "tests/support/config_defaults.h"

namespace cenote {
namespace {

const std::string kDefaultYaml = std::string(CENOTE_SOURCE_DIR) + "/config/default.yaml";

// Every key read by each section's read() into a default-constructed config, with its value.
YamlDefaults codeDefaults() {
  YamlDefaults defaults;
  test::recordSectionDefaults<pipeline::StereoConfig>(defaults, "stereo");
  test::recordSectionDefaults<pipeline::FusionConfig>(defaults, "fusion");
  test::recordSectionDefaults<pipeline::RunConfig>(defaults, "run");
  test::recordSectionDefaults<pipeline::RecordingConfig>(defaults, "bag");
  test::recordSectionDefaults<mapping::MapConfig>(defaults, "map");
  test::recordSectionDefaults<sim::SimConfig>(defaults, "sim");
  test::recordSectionDefaults<server::ServerConfig>(defaults, "server");
  return defaults;
}

void leaves(const YAML::Node& node, const std::string& prefix, std::vector<std::string>& out) {
  for (const auto& entry : node) {
    const std::string key = prefix.empty() ? entry.first.as<std::string>() : prefix + "." + entry.first.as<std::string>();
    if (entry.second.IsMap()) {
      leaves(entry.second, key, out);
    } else {
      out.push_back(key);
    }
  }
}

TEST(DefaultYaml, EveryKeyOfEverySectionEqualsTheCodeDefault) {
  const YamlDefaults defaults = codeDefaults();
  ASSERT_GT(defaults.entries.size(), 80u);  // stereo, fusion, run, map, sim, server (+ limits)
  test::expectFileHoldsDefaults(loadYamlFile(kDefaultYaml), "config/default.yaml", defaults);
}

TEST(DefaultYaml, EveryKeyOfTheFileIsOneTheCodeReads) {
  const YamlDefaults defaults = codeDefaults();
  std::vector<std::string> keys;
  leaves(loadYamlFile(kDefaultYaml), "", keys);
  EXPECT_GT(keys.size(), 80u);
  for (const std::string& key : keys) {
    EXPECT_EQ(defaults.entries.count(key), 1u) << key << ": in config/default.yaml but read by no config struct";
  }
}

TEST(DefaultYaml, LoadsIntoConfigsThatAreValid) {
  const pipeline::PipelineConfig pipeline = pipeline::PipelineConfig::load(kDefaultYaml);
  EXPECT_TRUE(pipeline.validate().empty());
  EXPECT_TRUE(pipeline::PipelineConfig{}.validate().empty());
  EXPECT_DOUBLE_EQ(pipeline.run.pose_max_gap_s, 0.25);
  EXPECT_TRUE(pipeline.stereo.lr_check);
  EXPECT_DOUBLE_EQ(pipeline.fusion.max_depth_m, 4.0);
}

}  // namespace
}  // namespace cenote
