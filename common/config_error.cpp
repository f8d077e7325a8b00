#include "common/config_error.h"

#include "common/error.h"

namespace cenote {

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
