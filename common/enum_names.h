// enum_names.h: one table of an enum's names serves both directions: toString() and parsing the name
// a config key or a command-line flag gives, with the error that lists the names allowed.
// A table is a constant array, in the order its names are listed in an error:
//   constexpr EnumName<PoseFrame> kPoseFrameNames[] = {{PoseFrame::kAuto, "auto"}, {PoseFrame::kBody, "body"}};
// Threads: constant tables and pure functions.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include "common/error.h"

namespace cenote {

template <typename Enum>
struct EnumName {
  Enum value;
  const char* name;
};

// How a parse error writes the names allowed: `auto, body or camera`, or `'cave', 'reef' or 'wreck'`.
enum class NameQuotes { kBare, kSingle };

// The name of `value` in `names`; `fallback` when the table has none (a value cast from an integer).
template <typename Enum, std::size_t N>
constexpr const char* enumName(const EnumName<Enum> (&names)[N], Enum value, const char* fallback = "?") {
  for (const EnumName<Enum>& n : names) {
    if (n.value == value) return n.name;
  }
  return fallback;
}

// The table's names in order: "a, b or c"; with NameQuotes::kSingle "'a', 'b' or 'c'".
template <typename Enum, std::size_t N>
std::string enumNameList(const EnumName<Enum> (&names)[N], NameQuotes quotes = NameQuotes::kBare) {
  const std::string quote = quotes == NameQuotes::kSingle ? "'" : "";
  std::string list;
  for (std::size_t i = 0; i < N; ++i) {
    if (i > 0) list += i + 1 == N ? " or " : ", ";
    list += quote + names[i].name + quote;
  }
  return list;
}

// The value whose name is `name` (exact, case-sensitive).
// @param subject what the error names first, e.g. "run.pose_frame = up" or "alignment 'up'".
// @throws Error (kInvalidArgument) "<subject>: must be <enumNameList(names, quotes)>" for any other name.
template <typename Enum, std::size_t N>
Enum parseEnumName(const EnumName<Enum> (&names)[N], std::string_view name, const std::string& subject,
                   NameQuotes quotes = NameQuotes::kBare) {
  for (const EnumName<Enum>& n : names) {
    if (name == n.name) return n.value;
  }
  throw Error(subject + ": must be " + enumNameList(names, quotes));
}

}  // namespace cenote
