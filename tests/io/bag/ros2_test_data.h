// ros2_test_data.h: what the ROS 2 recording tests share: the files tests/io/bag/gen wrote into
// CENOTE_ROS2_BAG_DATA (expected.json; cdr/<name>.cdr, one message of each type; the recordings),
// read as the tests compare them, and the check of a recording's topics against expected.json's.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "io/bag/recording.h"

namespace cenote::io::test {

using Bytes = std::vector<std::uint8_t>;

inline const std::filesystem::path kData = CENOTE_ROS2_BAG_DATA;

// expected.json, parsed once.
inline const nlohmann::json& expectedJson() {
  static const nlohmann::json json = [] {
    std::ifstream in(kData / "expected.json");
    return nlohmann::json::parse(in);
  }();
  return json;
}

// The CDR bytes of cdr/<name>.cdr and the values the serialiser wrote into them.
inline Bytes cdrSample(const std::string& name) {
  std::ifstream in(kData / "cdr" / (name + ".cdr"), std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), {});
}
inline const nlohmann::json& cdrValues(const std::string& name) { return expectedJson()["cdr"][name]["message"]; }

// A std_msgs/Header's stamp in nanoseconds.
inline std::int64_t stampOf(const nlohmann::json& header) {
  return header["stamp"]["sec"].get<std::int64_t>() * 1000000000 + header["stamp"]["nanosec"].get<std::int64_t>();
}

inline Bytes fromHex(const std::string& hex) {
  Bytes out(hex.size() / 2);
  for (std::size_t i = 0; i < out.size(); ++i)
    out[i] = static_cast<std::uint8_t>(std::stoi(hex.substr(2 * i, 2), nullptr, 16));
  return out;
}

// The recording's topics are expected.json's `want` (in the writer's order; topics() are sorted by
// name), each a CDR topic with its type, count and time span; the generators' /diagnostics (json
// encoded, neither CDR nor ROS 1) is not among them.
inline void expectTopics(const Recording& rec, nlohmann::json want) {
  std::sort(want.begin(), want.end(), [](const auto& a, const auto& b) { return a["name"] < b["name"]; });
  const std::vector<TopicInfo>& topics = rec.topics();
  ASSERT_EQ(topics.size(), want.size()) << "the json topic /diagnostics is not a topic";
  for (std::size_t i = 0; i < want.size(); ++i) {
    EXPECT_EQ(topics[i].name, want[i]["name"]);
    EXPECT_EQ(topics[i].type, want[i]["type"]) << topics[i].name;
    EXPECT_EQ(topics[i].encoding, MessageEncoding::kCdr) << topics[i].name;
    EXPECT_EQ(topics[i].message_count, want[i]["count"].get<std::uint64_t>()) << topics[i].name;
    EXPECT_EQ(topics[i].first_ns, std::stoll(want[i]["first_ns"].get<std::string>())) << topics[i].name;
    EXPECT_EQ(topics[i].last_ns, std::stoll(want[i]["last_ns"].get<std::string>())) << topics[i].name;
  }
}

}  // namespace cenote::io::test
