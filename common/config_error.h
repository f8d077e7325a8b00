// config_error.h: one failed configuration rule, and the helpers every config's validate() uses.
// A rule prints as  "stereo.max_disparity_px = 300: must be a multiple of 16 in [16, 256]".
#pragma once

#include <initializer_list>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

namespace cenote {

struct ConfigError {
  std::string key;    // dotted path, e.g. "stereo.window_px"
  std::string value;  // the offending value as text
  std::string rule;   // what is allowed

  std::string toString() const { return key + " = " + value + ": " + rule; }
};

// Collects failed rules; `check(ok, key, value, rule)` records one when `ok` is false.
class ConfigErrors {
 public:
  explicit ConfigErrors(std::string prefix) : prefix_(std::move(prefix)) {}

  template <typename T>
  void check(bool ok, const std::string& key, const T& value, const std::string& rule) {
    if (ok) return;
    std::ostringstream text;
    text << value;
    errors_.push_back({prefix_.empty() ? key : prefix_ + "." + key, text.str(), rule});
  }

  // check(lo <= value <= hi) with the rule "must be in [lo, hi]" followed by `note` (" (0: off)"),
  // the bounds printed as check() prints values. A NaN is outside every range.
  template <typename T>
  void checkRange(const std::string& key, const T& value, std::type_identity_t<T> lo, std::type_identity_t<T> hi,
                  const std::string& note = "") {
    if (value >= lo && value <= hi) return;
    std::ostringstream rule;
    rule << "must be in [" << lo << ", " << hi << "]" << note;
    check(false, key, value, rule.str());
  }

  std::vector<ConfigError> take() { return std::move(errors_); }

 private:
  std::string prefix_;
  std::vector<ConfigError> errors_;
};

// The errors of each list, in order: a config made of components validates as the sum of theirs.
std::vector<ConfigError> concatConfigErrors(std::initializer_list<std::vector<ConfigError>> lists);

// Joins errors one per line; empty string when there are none.
std::string formatConfigErrors(const std::vector<ConfigError>& errors);

// Throws cenote::Error listing every failed rule, when there is at least one.
void throwIfInvalid(const std::vector<ConfigError>& errors, const std::string& what);

}  // namespace cenote
