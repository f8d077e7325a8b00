#include "tests/support/config_defaults.h"

namespace cenote::test {

std::optional<YAML::Node> yamlAt(const YAML::Node& root, const std::string& dotted) {
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

void expectFileHoldsDefaults(const YAML::Node& root, const std::string& file, const YamlDefaults& defaults) {
  for (const auto& [key, entry] : defaults.entries) {
    const std::optional<YAML::Node> value = yamlAt(root, key);
    if (!value) {
      ADD_FAILURE() << key << ": missing from " << file << " (code default " << entry.shown << ")";
      continue;
    }
    EXPECT_TRUE(entry.equals(*value)) << key << ": " << file << " says " << YAML::Dump(*value) << ", the code's default is "
                                      << entry.shown;
  }
}

}  // namespace cenote::test
