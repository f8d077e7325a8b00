// config/default.yaml against the code's defaults: the file documents the defaults, the structs
// define them (a run without --config uses the structs), and the two must be the same value for
// every key of every section. The keys come from the config structs' own read() functions
// (YamlSection::recordDefaults), so a key added later is checked without touching this test.
#include <gtest/gtest.h>

#include <optional>
#include <string>
#include <vector>

#include "common/yaml_section.h"
#include "mapping/map_config.h"
#include "pipeline/dataset/recording_config.h"
#include "pipeline/runner/run_config.h"
#include "server/server_config.h"
#include "sim/sim_config.h"

namespace cenote {
namespace {

const std::string kDefaultYaml = std::string(CENOTE_SOURCE_DIR) + "/config/default.yaml";

// Reads the section `key` into a default-constructed Config; `top` records each key's value.
template <typename Config>
void recordSection(YamlSection& top, const std::string& key) {
  Config config;
  top.readSection(key, config);
}

// Every key read by each section's read() into a default-constructed config, with its value.
YamlDefaults codeDefaults() {
  YamlDefaults defaults;
  YamlSection top(YAML::Node(), "", "code defaults");
  top.recordDefaults(&defaults);
  recordSection<pipeline::StereoConfig>(top, "stereo");
  recordSection<pipeline::FusionConfig>(top, "fusion");
  recordSection<pipeline::RunConfig>(top, "run");
  recordSection<pipeline::RecordingConfig>(top, "bag");
  recordSection<mapping::MapConfig>(top, "map");
  recordSection<sim::SimConfig>(top, "sim");
  recordSection<server::ServerConfig>(top, "server");
  return defaults;
}

// The value at a dotted key of the file ("server.limits.max_batch"), if there is one.
std::optional<YAML::Node> at(const YAML::Node& root, const std::string& dotted) {
  YAML::Node node = YAML::Clone(root);
  size_t begin = 0;
  while (true) {
    const size_t dot = dotted.find('.', begin);
    const std::string key = dotted.substr(begin, dot == std::string::npos ? std::string::npos : dot - begin);
    if (!node.IsMap() || !node[key]) return std::nullopt;
    node = node[key];
    if (dot == std::string::npos) return node;
    begin = dot + 1;
  }
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
  const YAML::Node root = loadYamlFile(kDefaultYaml);
  for (const auto& [key, entry] : defaults.entries) {
    const std::optional<YAML::Node> value = at(root, key);
    if (!value) {
      ADD_FAILURE() << key << ": missing from config/default.yaml (code default " << entry.shown << ")";
      continue;
    }
    EXPECT_TRUE(entry.equals(*value)) << key << ": config/default.yaml says " << YAML::Dump(*value)
                                      << ", the code's default is " << entry.shown;
  }
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
