#include "common/size_format.h"

#include <array>
#include <cstdio>

namespace cenote {
namespace {

// `value` in the largest of `units` (each `step` times the one before) that keeps it below `step`,
// with three significant digits; the first unit (the value itself) prints as a whole number.
template <std::size_t N>
std::string format(double value, double step, const std::array<const char*, N>& units) {
  if (!(value >= 0.0)) return "unknown";
  std::size_t unit = 0;
  while (value >= step && unit + 1 < N) {
    value /= step;
    ++unit;
  }
  const char* spacing = *units[unit] == '\0' ? "" : " ";
  char text[48];
  if (unit == 0) {
    std::snprintf(text, sizeof(text), "%.0f%s%s", value, spacing, units[unit]);
  } else {
    const int decimals = value < 10.0 ? 2 : value < 100.0 ? 1 : 0;
    std::snprintf(text, sizeof(text), "%.*f%s%s", decimals, value, spacing, units[unit]);
  }
  return text;
}

}  // namespace

std::string formatBytes(double bytes) {
  return format(bytes, 1024.0, std::array<const char*, 6>{"B", "KiB", "MiB", "GiB", "TiB", "PiB"});
}

std::string formatCount(double count) {
  return format(count, 1000.0, std::array<const char*, 6>{"", "k", "M", "G", "T", "P"});
}

}  // namespace cenote
