#include "io/bag/db3_metadata.h"

#include <algorithm>
#include <cctype>

#include "common/error.h"
#include "common/yaml_section.h"
#include "io/bag/mcap_recording.h"

namespace cenote::io {
namespace {

namespace fs = std::filesystem;

std::string text(const YAML::Node& node) { return node ? node.as<std::string>() : ""; }

std::string upper(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return s;
}

Db3Compression compressionOf(const YAML::Node& info, const std::string& where) {
  const std::string mode = text(info["compression_mode"]);
  const std::string format = text(info["compression_format"]);
  Db3Compression compression = Db3Compression::kNone;
  if (upper(mode) == "FILE") {
    compression = Db3Compression::kFile;
  } else if (upper(mode) == "MESSAGE") {
    compression = Db3Compression::kMessage;
  } else if (!mode.empty() && upper(mode) != "NONE") {
    throw IoError(where + ".compression_mode is '" + mode + "': rosbag2 writes NONE, FILE or MESSAGE");
  }
  if (compression != Db3Compression::kNone && format != "zstd") {
    throw IoError(where + ".compression_format is '" + format + "' (compression_mode " + mode +
                  "): this reader decompresses zstd, the compressor rosbag2 ships; decompress the bag first (ros2 bag "
                  "convert)");
  }
  return compression;
}

// topics_with_message_count, each topic spanning the bag's starting_time .. + duration.
std::vector<TopicInfo> topicsOf(const YAML::Node& info, const std::string& where) {
  const YAML::Node list = info["topics_with_message_count"];
  if (!list || !list.IsSequence()) throw IoError(where + ".topics_with_message_count: expected a list of topics");
  const YAML::Node start = info["starting_time"]["nanoseconds_since_epoch"];
  const YAML::Node duration = info["duration"]["nanoseconds"];
  const std::int64_t first = start ? start.as<std::int64_t>() : 0;
  const std::int64_t last = first + (duration ? duration.as<std::int64_t>() : 0);
  std::vector<TopicInfo> topics;
  for (const YAML::Node& entry : list) {
    const YAML::Node meta = entry["topic_metadata"];
    MessageEncoding encoding{};
    if (!meta || !db3Encoding(text(meta["serialization_format"]), encoding)) continue;
    topics.push_back(TopicInfo{text(meta["name"]), ros1TypeName(text(meta["type"])), encoding,
                               entry["message_count"] ? entry["message_count"].as<std::uint64_t>() : 0, first, last});
  }
  sortTopicsByName(topics);
  return topics;
}

}  // namespace

bool db3Encoding(const std::string& serialization_format, MessageEncoding& encoding) {
  if (serialization_format == "cdr") encoding = MessageEncoding::kCdr;
  else if (serialization_format == "ros1") encoding = MessageEncoding::kRos1;
  else return false;
  return true;
}

Db3Metadata readDb3Metadata(const fs::path& bag_folder) {
  const fs::path file = bag_folder / "metadata.yaml";
  const YAML::Node root = loadYamlFile(file.string());
  // A document that is not a mapping (a scalar) has no keys to look up: yaml-cpp throws at the lookup.
  const YAML::Node info = root.IsMap() ? root["rosbag2_bagfile_information"] : YAML::Node();
  const std::string where = file.string() + ": rosbag2_bagfile_information";
  if (!info || !info.IsMap()) throw IoError(file.string() + ": no rosbag2_bagfile_information mapping");
  try {
    const std::string storage = info["storage_identifier"] ? text(info["storage_identifier"]) : "sqlite3";
    if (storage != "sqlite3") {
      throw IoError(where + ".storage_identifier is '" + storage +
                    "'; this reader reads sqlite3 (open an mcap bag's .mcap file itself)");
    }
    Db3Metadata out;
    out.compression = compressionOf(info, where);
    const YAML::Node paths = info["relative_file_paths"];
    if (!paths || !paths.IsSequence() || paths.size() == 0) {
      throw IoError(where + ".relative_file_paths: expected a non-empty list of .db3 files");
    }
    for (const YAML::Node& p : paths) out.files.push_back(bag_folder / p.as<std::string>());
    if (out.compression == Db3Compression::kFile) out.topics = topicsOf(info, where);
    return out;
  } catch (const YAML::Exception& e) {
    throw IoError(where + ": " + e.what());
  }
}

}  // namespace cenote::io
