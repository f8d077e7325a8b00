// yaml_section.h: strict reading of one YAML mapping into a typed config struct.
// Every key read is remembered; finish() rejects any key that was not read, so a typo such as
// `stereo.window_sise` is an error naming the file and the key, never a silent default.
// A value of the wrong type is an error naming the key and the expected type.
#pragma once

#include <yaml-cpp/yaml.h>

#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include "common/error.h"

namespace cenote {

// The values that read() found in the variables it was given (a default-constructed config's
// defaults), by dotted key ("stereo.lr_check"): what lets a test compare config/default.yaml with
// the code's defaults key by key, including keys added later.
struct YamlDefaults {
  struct Entry {
    std::string shown;                              // the value as text
    std::function<bool(const YAML::Node&)> equals;  // whether a YAML value reads as the same value
  };
  std::map<std::string, Entry> entries;
};

class YamlSection {
 public:
  // `node` must be a mapping (or null: an absent section keeps every default).
  // `path` is the dotted name used in messages ("stereo"), `file` the source file name.
  // @throws Error when node is neither a mapping nor null.
  YamlSection(const YAML::Node& node, std::string path, std::string file);

  // Reads `key` into `value` when present; leaves `value` unchanged when absent.
  // @throws Error when the value cannot be converted to T.
  template <typename T>
  void read(const std::string& key, T& value) {
    seen_.insert(key);
    if (defaults_ != nullptr) record(key, value);
    if (!node_ || node_.IsNull()) return;
    const YAML::Node child = node_[key];
    if (!child) return;
    try {
      value = child.as<T>();
    } catch (const YAML::Exception&) {
      throw Error(file_ + ": " + path_ + "." + key + " = '" + YAML::Dump(child) + "': expected " + typeName<T>());
    }
  }

  // Reads `key` as a name into the enum `value`: the name is read as a string (absent: toString(value),
  // found by argument-dependent lookup) and `value = parse(name)`.
  // @throws what `parse` throws for a name it does not know.
  template <typename Enum, typename Parse>
  void readName(const std::string& key, Enum& value, Parse parse) {
    std::string name = toString(value);
    read(key, name);
    value = parse(name);
  }

  // The sub-mapping `key` as a section of its own (which the caller must finish()).
  YamlSection section(const std::string& key);

  // Reads the sub-mapping `key` into `config` with its `read(YamlSection&)`, then finishes it.
  // @throws Error as read() does, and for a key of the sub-mapping that config.read() does not read.
  template <typename Config>
  void readSection(const std::string& key, Config& config) {
    YamlSection sub = section(key);
    config.read(sub);
    sub.finish();
  }

  // @throws Error naming every key of the mapping that was never read.
  void finish() const;

  // From now on, each read() (here and in sections made from this one) first records the value
  // its variable holds into `defaults` (not owned; must outlive the section).
  void recordDefaults(YamlDefaults* defaults) { defaults_ = defaults; }

 private:
  template <typename T>
  static const char* typeName() {
    if constexpr (std::is_same_v<T, bool>) return "true or false";
    else if constexpr (std::is_integral_v<T>) return "an integer";
    else if constexpr (std::is_floating_point_v<T>) return "a number";
    else return "a string";
  }

  template <typename T>
  void record(const std::string& key, const T& value) {
    std::ostringstream shown;
    shown << std::boolalpha << value;
    defaults_->entries[path_.empty() ? key : path_ + "." + key] = {shown.str(), [value](const YAML::Node& node) {
                                                                     try {
                                                                       return node.as<T>() == value;
                                                                     } catch (const YAML::Exception&) {
                                                                       return false;
                                                                     }
                                                                   }};
  }

  YamlDefaults* defaults_ = nullptr;
  YAML::Node node_;
  std::string path_;
  std::string file_;
  std::set<std::string> seen_;
};

// Loads a YAML file. @throws Error when missing or unparsable (with the line of the error).
YAML::Node loadYamlFile(const std::string& path);

// Reads the section `key` of the YAML file at `path` into `config` (YamlSection::readSection); other
// top-level keys of the file are left to their own readers.
// @throws Error when the file is missing or unparsable, or the section is wrong.
template <typename Config>
void readConfigFile(const std::string& path, const std::string& key, Config& config) {
  YamlSection(loadYamlFile(path), "", path).readSection(key, config);
}

}  // namespace cenote
