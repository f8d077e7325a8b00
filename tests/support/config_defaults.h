// config_defaults.h: a YAML file's config sections against the code's defaults, key by key. The keys
// and their default values come from the config structs' own read() (YamlSection::recordDefaults),
// so a key added later is checked without touching the tests that use this.
#pragma once

#include <gtest/gtest.h>

#include <optional>
#include <string>

#include "common/yaml_section.h"

namespace cenote::test {

// Records every key that Config::read() reads in section `key`, with a default-constructed
// Config's value, into `defaults`.
template <typename Config>
void recordSectionDefaults(YamlDefaults& defaults, const std::string& key) {
  YamlSection top(YAML::Node(), "", "code defaults");
  top.recordDefaults(&defaults);
  Config config;
  top.readSection(key, config);
}

// The value at a dotted key of `root` ("server.limits.max_batch"), if there is one.
std::optional<YAML::Node> yamlAt(const YAML::Node& root, const std::string& dotted);

// Fails the test for each key of `defaults` that the file `root` (named `file` in messages) lacks or
// sets to another value.
void expectFileHoldsDefaults(const YAML::Node& root, const std::string& file, const YamlDefaults& defaults);

}  // namespace cenote::test
