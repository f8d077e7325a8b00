#include "common/config_error.h"

#include "common/error.h"

namespace cenote {

std::vector<ConfigError> concatConfigErrors(std::initializer_list<std::vector<ConfigError>> lists) {
  std::vector<ConfigError> all;
  for (const std::vector<ConfigError>& list : lists) all.insert(all.end(), list.begin(), list.end());
  return all;
}

std::string formatConfigErrors(const std::vector<ConfigError>& errors) {
  std::string text;
  for (const ConfigError& error : errors) {
    if (!text.empty()) text += '\n';
    text += error.toString();
  }
  return text;
}

void throwIfInvalid(const std::vector<ConfigError>& errors, const std::string& what) {
  if (errors.empty()) return;
  throw Error("invalid " + what + ":\n" + formatConfigErrors(errors));
}

}  // namespace cenote
