#include "pipeline/dataset/recording_config.h"

#include <algorithm>

#include "common/yaml_section.h"

namespace cenote::pipeline {

std::vector<ConfigError> RecordingConfig::validate() const {
  ConfigErrors errors("bag");
  errors.check(sync_tolerance_s >= 0.0 && sync_tolerance_s < 1.0, "sync_tolerance_s", sync_tolerance_s,
               "must be in [0, 1)");
  errors.checkRange("sync_queue", sync_queue, 2, 4096);
  errors.checkRange("image_bits", image_bits, 9, 16);
  const bool known = rig == "auto" ||
                     std::any_of(rigs.begin(), rigs.end(), [&](const RigPreset& p) { return p.name == rig; });
  errors.check(known, "rig", rig, "must be auto or one of the names under bag.rigs");
  for (const RigPreset& p : rigs) {
    errors.check(!p.left.empty() && !p.right.empty() && p.left != p.right, "rigs." + p.name, p.left + " " + p.right,
                 "needs two different topics");
  }
  return errors.take();
}

void RecordingConfig::read(YamlSection& section) {
  section.read("sync_tolerance_s", sync_tolerance_s);
  section.read("sync_queue", sync_queue);
  section.read("image_bits", image_bits);
  section.read("rig", rig);
  YamlSection presets = section.section("rigs");
  for (RigPreset& p : rigs) {
    YamlSection one = presets.section(p.name);
    one.read("left", p.left);
    one.read("right", p.right);
    one.finish();
  }
  presets.finish();
}

}  // namespace cenote::pipeline
