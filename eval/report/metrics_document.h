// metrics_document.h: the JSON of the metrics files of `cenote eval` (depth, cloud, trajectory,
// map): their common head and their numbers. For the .cpp files that write them (nlohmann's header
// stays out of the public headers).
// Threads: pure functions.
#pragma once

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

namespace cenote::eval {

using Json = nlohmann::ordered_json;

// A finite number as itself, NaN and infinity as null (JSON has no such numbers).
inline Json jsonNumber(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

// {"kind": kind, "units": units, "inputs": {"estimate": estimate, "reference": reference}}: how every
// metrics file starts; the caller adds its numbers.
inline Json metricsDocument(const std::string& kind, const std::string& units, const std::string& estimate,
                            const std::string& reference) {
  Json j;
  j["kind"] = kind;
  j["units"] = units;
  j["inputs"] = {{"estimate", estimate}, {"reference", reference}};
  return j;
}

}  // namespace cenote::eval
