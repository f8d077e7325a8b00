// error.h: the one exception type that cenote's libraries throw for bad input.
// A message says what was wrong, where, and what was allowed, e.g.
//   "stereo: right image is 800x599 but left is 800x600"
// Library code never ends the process; the command-line programs catch Error, print it and exit non-zero.
#pragma once

#include <stdexcept>
#include <string>

namespace cenote {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace cenote
