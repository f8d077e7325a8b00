#include "io/bag/recording.h"

#include <algorithm>
#include <cstring>
#include <fstream>

#include "common/error.h"
#include "io/bag/db3_recording.h"
#include "io/bag/mcap_recording.h"
#include "io/bag/ros1_bag.h"

namespace cenote::io {

std::string describeSkippedChunk(const std::string& damage,
                                 const std::vector<std::pair<std::string, std::uint64_t>>& held) {
  if (held.empty()) return damage + " (its messages unknown: no index records follow it)";
  std::uint64_t total = 0;
  std::string list;
  for (const auto& [topic, n] : held) {
    list += (list.empty() ? " " : ", ") + std::to_string(n) + " on " + topic;
    total += n;
  }
  return damage + " (of its " + std::to_string(total) + " messages:" + list + ")";
}

std::vector<int> sortTopicsByName(std::vector<TopicInfo>& topics) {
  std::vector<int> order(topics.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return topics[a].name < topics[b].name; });
  std::vector<int> rank(order.size());
  std::vector<TopicInfo> sorted;
  sorted.reserve(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    rank[order[i]] = static_cast<int>(i);
    sorted.push_back(std::move(topics[order[i]]));
  }
  topics = std::move(sorted);
  return rank;
}

bool isRos2BagFolder(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_directory(path, ec)) return false;
  if (std::filesystem::exists(path / "metadata.yaml", ec)) return true;
  for (const auto& entry : std::filesystem::directory_iterator(path, ec))
    if (isDb3FileName(entry.path())) return true;  // a recording never finished
  return false;
}

std::unique_ptr<Recording> openRecording(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw NotFoundError("cannot read recording " + path.string() + ": no such file");
  if (std::filesystem::is_directory(path, ec)) {
    if (isRos2BagFolder(path)) return openDb3Recording(path);
    throw Error("recording " + path.string() + ": a folder, but not a ROS 2 bag (no metadata.yaml, no .db3 file)");
  }
  char head[16] = {};
  std::ifstream in(path, std::ios::binary);
  if (!in) throwReadError(path.string(), "permission denied", "recording ");
  in.read(head, sizeof(head));
  const std::size_t n = static_cast<std::size_t>(in.gcount());
  if (n >= 9 && std::memcmp(head, "#ROSBAG V", 9) == 0) return std::make_unique<Ros1Bag>(path);
  if (n >= 8 && std::memcmp(head, "\x89MCAP0\r\n", 8) == 0) return openMcapRecording(path);
  if (n >= 16 && std::memcmp(head, "SQLite format 3", 16) == 0) return openDb3Recording(path);
  if (n >= 4 && std::memcmp(head, "\x28\xB5\x2F\xFD", 4) == 0 && isDb3FileName(path)) return openDb3Recording(path);
  throw IoError("recording " + path.string() +
                ": not a ROS 1 bag ('#ROSBAG V2.0'), an MCAP file or a ROS 2 bag (.db3, .db3.zstd, or a folder with "
                "metadata.yaml)");
}

}  // namespace cenote::io
