// text_parse.h: numbers and points typed on a command line: "1.5,-2,0.25".
// Each item is one whole number as strtod reads it (leading blanks allowed, nothing after it);
// an empty item is not a number. Callers word their own errors (they name their option).
// Units: whatever the caller's option is in (metres for points). Threads: pure functions.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

namespace cenote {

// Splits `text` at `separator` as std::getline does (a trailing separator ends the list, "" is no
// item) and parses each item. @return false, with the offending item in `*bad_item` when given,
// at the first item that is not a number; `values` then holds the numbers before it.
bool parseNumberList(const std::string& text, char separator, std::vector<double>& values, std::string* bad_item = nullptr);

// "x,y,z": exactly three comma-separated numbers; nullopt otherwise.
std::optional<Eigen::Vector3d> parsePoint(const std::string& text);

}  // namespace cenote
