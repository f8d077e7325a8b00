#include "common/yaml_section.h"

#include <filesystem>

namespace cenote {

YamlSection::YamlSection(const YAML::Node& node, std::string path, std::string file)
    : node_(node), path_(std::move(path)), file_(std::move(file)) {
  if (node_ && !node_.IsNull() && !node_.IsMap()) {
    throw Error(file_ + ": " + path_ + " must be a mapping of keys to values");
  }
}

YamlSection YamlSection::section(const std::string& key) {
  seen_.insert(key);
  YAML::Node child = (node_ && !node_.IsNull()) ? node_[key] : YAML::Node();
  YamlSection sub(child, path_.empty() ? key : path_ + "." + key, file_);
  sub.defaults_ = defaults_;
  return sub;
}

void YamlSection::finish() const {
  if (!node_ || node_.IsNull()) return;
  std::string unknown;
  for (const auto& entry : node_) {
    // A YAML key may itself be a list or a mapping (`? [a, b]`): never one of ours.
    if (!entry.first.IsScalar()) {
      throw Error(file_ + ": " + (path_.empty() ? std::string("the top level") : path_) +
                  " has a key that is not a name: " + YAML::Dump(entry.first));
    }
    const std::string key = entry.first.as<std::string>();
    if (seen_.count(key) == 0) {
      if (!unknown.empty()) unknown += ", ";
      unknown += path_.empty() ? key : path_ + "." + key;
    }
  }
  if (!unknown.empty()) throw Error(file_ + ": unknown configuration key(s): " + unknown);
}

YAML::Node loadYamlFile(const std::string& path) {
  if (!std::filesystem::exists(path)) throw NotFoundError("config file not found: " + path);
  try {
    return YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw Error(path + ": not valid YAML: " + e.what());
  }
}

}  // namespace cenote
