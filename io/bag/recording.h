#pragma once
// A recorded robot log (ROS 1 bag, ROS 2 MCAP or sqlite3 .db3), read front to back in one pass with
// memory independent of its length. The containers differ; what they hand on is the same: topics and
// messages, each message's bytes serialised as ROS 1 or CDR (parsed by io/bag/ros_messages.h).

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace cenote::io {

/// How a message's bytes are serialised.
enum class MessageEncoding { kRos1, kCdr };

/// One topic of a recording, as `rosbag info` lists it.
struct TopicInfo {
  std::string name;  ///< "/slave1/image_raw/compressed"
  std::string type;  ///< ROS 1 spelling: "sensor_msgs/CompressedImage" (ROS 2's "pkg/msg/T" becomes "pkg/T")
  MessageEncoding encoding = MessageEncoding::kRos1;
  std::uint64_t message_count = 0;  ///< from the index or summary; for a recording cut short, what a scan found
  std::int64_t first_ns = 0;        ///< log time of the first and last message
  std::int64_t last_ns = 0;
};

/// One message. `data` stays valid until the next call to Recording::next().
struct RecordedMessage {
  const TopicInfo* topic = nullptr;
  std::int64_t log_time_ns = 0;
  std::span<const std::uint8_t> data;
  std::uint64_t file_offset = 0;  ///< where its record (or chunk) starts in the file, for error messages
};

/// A recording opened for one pass. Messages come in file order (the order the recorder wrote them).
class Recording {
 public:
  virtual ~Recording() = default;

  /// Every topic, known after open (from the index or summary, or from a scan when the file has none).
  virtual const std::vector<TopicInfo>& topics() const = 0;

  /// Reads the next message of a topic in `wanted` (all topics when empty); false at the end.
  /// Throws IoError naming the file and offset for damage it cannot step over.
  virtual bool next(const std::vector<std::string>& wanted, RecordedMessage& out) = 0;

  /// Empty for a whole file; otherwise where and why reading stopped short ("cut at byte 123456: no
  /// index; 812 complete messages read"), as `rosbag reindex` would report it.
  virtual std::string truncation() const = 0;

  /// The damage reading stepped over so far, one line each, naming the file, the byte offset and
  /// what was lost ("bag dive.bag, byte 1234 (chunk): bz2 data are corrupt (...); skipped the chunk
  /// (of its 24 messages: 12 on /left, 12 on /right)"). A damaged chunk loses its messages, not the rest.
  virtual std::vector<std::string> skipped() const { return {}; }

  /// How the container as a whole is compressed, for a person, when it says more than its chunks do
  /// (a rosbag2 bag: "zstd by message", "zstd by file: ..." with where the copies go); empty otherwise.
  virtual std::string compression() const { return ""; }
};

/// One line of Recording::skipped(): `damage` ("...; skipped the chunk"), then the messages the
/// file's index says the chunk held, by topic in the order given ("(of its 24 messages: 12 on /left,
/// 12 on /right)"); `held` empty: "(its messages unknown: no index records follow it)".
std::string describeSkippedChunk(const std::string& damage, const std::vector<std::pair<std::string, std::uint64_t>>& held);

/// Sorts `topics` by name, as `rosbag info` lists them. @return where each topic went: the new index
/// of the topic that was at index i.
std::vector<int> sortTopicsByName(std::vector<TopicInfo>& topics);

/// Whether `path` is a ROS 2 bag folder: metadata.yaml (with .db3 files, or .db3.zstd ones when
/// compressed by file), or .db3 / .db3.zstd files alone (a recorder that never finished).
bool isRos2BagFolder(const std::filesystem::path& path);

/// Opens a .bag (ROS 1, format 2.0), .mcap or a ROS 2 bag folder / .db3, told apart by their first bytes
/// (a folder by its metadata.yaml). Throws NotFoundError or IoError with a message naming the path.
std::unique_ptr<Recording> openRecording(const std::filesystem::path& path);

}  // namespace cenote::io
