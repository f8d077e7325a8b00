#include "io/bag/mcap_recording.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <unordered_map>

#include "common/error.h"
#include "io/bag/mcap_records.h"

namespace cenote::io {
namespace {

using detail::Fields;
using detail::kChannel;
using detail::kChunkIndex;
using detail::kFooter;
using detail::kMagic;
using detail::kMessageIndex;
using detail::kRecordHeader;
using detail::kSchema;
using detail::kStatistics;
using detail::Malformed;
using detail::RawMessage;
using detail::RecordCursor;
struct SchemaInfo {
  std::string name;
};

class McapRecording final : public Recording {
 public:
  explicit McapRecording(const std::filesystem::path& path);

  const std::vector<TopicInfo>& topics() const override { return topics_; }
  bool next(const std::vector<std::string>& wanted, RecordedMessage& out) override;
  std::string truncation() const override { return truncation_; }
  std::vector<std::string> skipped() const override { return skipped_; }

 private:
  void noteSkips();
  void define(std::uint8_t op, Fields& f, bool create_topics);
  bool readSummary();
  void scan();

  std::filesystem::path path_;
  std::uint64_t file_size_ = 0;
  std::vector<TopicInfo> topics_;
  std::unordered_map<std::uint16_t, SchemaInfo> schemas_;
  std::unordered_map<std::uint16_t, int> channel_topic_;  // channel id -> index in topics_, -1: not a topic
  std::string truncation_;
  std::vector<std::string> skipped_;
  std::optional<RecordCursor> cursor_;
};

McapRecording::McapRecording(const std::filesystem::path& path) : path_(path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throwReadError(path.string(), "not a file", "MCAP file ");
  file_size_ = std::filesystem::file_size(path, ec);
  std::uint8_t magic[8] = {};
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) throwReadError(path.string(), "cannot open", "MCAP file ");
    in.read(reinterpret_cast<char*>(magic), sizeof magic);
    if (in.gcount() != sizeof magic || std::memcmp(magic, kMagic, sizeof magic) != 0)
      throw IoError(path.string() +
                    ": not an MCAP file (its first 8 bytes are not the MCAP magic 89 4d 43 41 50 30 0d 0a)");
  }
  if (!readSummary()) scan();
  const std::vector<int> rank = sortTopicsByName(topics_);
  for (auto& [channel, topic] : channel_topic_)
    if (topic >= 0) topic = rank[topic];
  cursor_.emplace(path_, file_size_, [this](std::uint8_t op, Fields& f, std::uint64_t) { define(op, f, false); });
}

// Schema and Channel records. A channel of encoding "cdr" or "ros1" becomes a topic (one per topic name
// and type) when `create_topics`; afterwards only channels already known map to topics.
void McapRecording::define(std::uint8_t op, Fields& f, bool create_topics) {
  if (op == kSchema) {
    const std::uint16_t id = f.u16();
    SchemaInfo info{f.str()};
    schemas_.try_emplace(id, std::move(info));
    return;
  }
  const std::uint16_t id = f.u16();
  const std::uint16_t schema_id = f.u16();
  const std::string topic = f.str();
  const std::string encoding = f.str();
  if (channel_topic_.count(id) || !create_topics) return;
  if (encoding != "cdr" && encoding != "ros1") {
    channel_topic_[id] = -1;
    return;
  }
  const auto schema = schemas_.find(schema_id);
  const std::string type = schema == schemas_.end() ? std::string() : ros1TypeName(schema->second.name);
  const MessageEncoding enc = encoding == "cdr" ? MessageEncoding::kCdr : MessageEncoding::kRos1;
  for (std::size_t i = 0; i < topics_.size(); ++i)
    if (topics_[i].name == topic && topics_[i].type == type && topics_[i].encoding == enc) {
      channel_topic_[id] = static_cast<int>(i);
      return;
    }
  TopicInfo info;
  info.name = topic;
  info.type = type;
  info.encoding = enc;
  topics_.push_back(info);
  channel_topic_[id] = static_cast<int>(topics_.size() - 1);
}

// Counts every message of the data section (a file without a usable summary, or one cut short).
void McapRecording::scan() {
  topics_.clear();
  channel_topic_.clear();
  schemas_.clear();
  RecordCursor cursor(path_, file_size_, [this](std::uint8_t op, Fields& f, std::uint64_t) { define(op, f, true); });
  RawMessage raw;
  std::uint64_t messages = 0;
  while (cursor.next(raw)) {
    const auto it = channel_topic_.find(raw.channel);
    if (it == channel_topic_.end() || it->second < 0) continue;
    ++messages;
    TopicInfo& t = topics_[it->second];
    if (t.message_count == 0 || raw.log_time_ns < t.first_ns) t.first_ns = raw.log_time_ns;
    if (t.message_count == 0 || raw.log_time_ns > t.last_ns) t.last_ns = raw.log_time_ns;
    ++t.message_count;
  }
  if (!cursor.cut().empty()) truncation_ = cursor.cut() + "; " + std::to_string(messages) + " complete messages read";
}

}  // namespace

std::string ros1TypeName(const std::string& ros2_type) {
  const std::size_t at = ros2_type.find("/msg/");
  if (at == std::string::npos) return ros2_type;
  return ros2_type.substr(0, at) + "/" + ros2_type.substr(at + 5);
}

namespace {

// Topics and counts from the summary section: Schema and Channel records, and the Message Index
// records of every chunk the Chunk Index records list (exact counts and time spans). False, with
// nothing kept, when the file has no summary or the summary does not account for every message the
// Statistics record counts (messages outside chunks, chunks without message indexes): then a scan.
bool McapRecording::readSummary() {
  constexpr std::uint64_t kFooterRecord = kRecordHeader + 20;
  if (file_size_ < 2 * sizeof kMagic + kFooterRecord) return false;
  std::ifstream in(path_, std::ios::binary);
  auto readAt = [&](std::uint64_t at, std::uint8_t* dst, std::uint64_t n) {
    in.clear();
    in.seekg(static_cast<std::streamoff>(at));
    in.read(reinterpret_cast<char*>(dst), static_cast<std::streamsize>(n));
    return static_cast<std::uint64_t>(in.gcount()) == n;
  };
  std::uint8_t tail[kFooterRecord + sizeof kMagic];
  const std::uint64_t footer_at = file_size_ - sizeof tail;
  if (!readAt(footer_at, tail, sizeof tail)) return false;
  if (std::memcmp(tail + kFooterRecord, kMagic, sizeof kMagic) != 0 || tail[0] != kFooter) return false;
  Fields footer(std::span<const std::uint8_t>(tail + kRecordHeader, 20));
  const std::uint64_t summary_start = footer.u64();
  const std::uint64_t summary_offset_start = footer.u64();
  if (summary_start == 0) return false;
  const std::uint64_t summary_end = summary_offset_start != 0 ? summary_offset_start : footer_at;
  const std::string where = path_.string() + ": summary";
  if (summary_start < sizeof kMagic || summary_end > footer_at || summary_start > summary_end)
    throw IoError(where + " at byte " + std::to_string(summary_start) + " lies outside the file's " +
                  std::to_string(file_size_) + " bytes");

  struct ChunkRef {
    std::uint64_t start, length, index_length;
  };
  std::vector<ChunkRef> chunks;
  std::optional<std::uint64_t> statistics_count;
  std::vector<std::uint8_t> record;
  for (std::uint64_t at = summary_start; at < summary_end;) {
    std::uint8_t head[kRecordHeader];
    if (summary_end - at < kRecordHeader || !readAt(at, head, kRecordHeader))
      throw IoError(where + " record at byte " + std::to_string(at) + " runs past the summary's end");
    std::uint64_t len = 0;
    for (int i = 0; i < 8; ++i) len |= std::uint64_t{head[1 + i]} << (8 * i);
    if (len > summary_end - at - kRecordHeader)
      throw IoError(where + " record at byte " + std::to_string(at) + " of " + std::to_string(len) +
                    " bytes runs past the summary's end");
    const std::uint8_t op = head[0];
    if (op == kSchema || op == kChannel || op == kStatistics || op == kChunkIndex) {
      record.resize(len);
      readAt(at + kRecordHeader, record.data(), len);
      Fields f(record);
      try {
        if (op == kStatistics) {
          statistics_count = f.u64();
        } else if (op == kChunkIndex) {
          f.u64();  // message start time
          f.u64();  // message end time
          ChunkRef c{};
          c.start = f.u64();
          c.length = f.u64();
          f.bytes(f.u32(), "message index offsets");
          c.index_length = f.u64();
          chunks.push_back(c);
        } else {
          define(op, f, true);
        }
      } catch (const Malformed& m) {
        throw IoError(where + " record at byte " + std::to_string(at) + ": " + m.what);
      }
    }
    at += kRecordHeader + len;
  }
  auto giveUp = [&] {
    topics_.clear();
    channel_topic_.clear();
    schemas_.clear();
    return false;
  };
  if (!statistics_count) return giveUp();

  std::uint64_t indexed = 0;
  for (const ChunkRef& c : chunks) {
    if (c.index_length == 0) return giveUp();
    const std::uint64_t index_at = c.start + c.length;
    if (c.start < sizeof kMagic || index_at < c.start || index_at > summary_start ||
        c.index_length > summary_start - index_at)
      throw IoError(where + ": chunk index of the chunk at byte " + std::to_string(c.start) +
                    " points past the data section");
    record.resize(c.index_length);
    readAt(index_at, record.data(), c.index_length);
    Fields all(record);
    try {
      while (!all.atEnd()) {
        const std::uint8_t op = all.bytes(1, "opcode")[0];
        Fields f(all.bytes(all.u64(), "message index"));
        if (op != kMessageIndex) continue;
        const std::uint16_t channel = f.u16();
        const std::uint32_t bytes = f.u32();
        Fields entries(f.bytes(bytes, "message index entries"));
        const auto it = channel_topic_.find(channel);
        TopicInfo* t = it == channel_topic_.end() || it->second < 0 ? nullptr : &topics_[it->second];
        for (std::uint32_t i = 0; i < bytes / 16; ++i) {
          const std::int64_t log_time = static_cast<std::int64_t>(entries.u64());
          entries.u64();  // offset in the chunk
          ++indexed;
          if (!t) continue;
          if (t->message_count == 0 || log_time < t->first_ns) t->first_ns = log_time;
          if (t->message_count == 0 || log_time > t->last_ns) t->last_ns = log_time;
          ++t->message_count;
        }
      }
    } catch (const Malformed& m) {
      throw IoError(path_.string() + ": message index at byte " + std::to_string(index_at) + ": " + m.what);
    }
  }
  if (indexed != *statistics_count) return giveUp();
  return true;
}

// The cursor's new skipped chunks, as a ROS 1 bag names them: "<damage>; skipped the chunk (of its N
// messages: n on /topic, ...)", the channels by topic.
void McapRecording::noteSkips() {
  for (std::size_t i = skipped_.size(); i < cursor_->skipped().size(); ++i) {
    const RecordCursor::SkippedChunk& chunk = cursor_->skipped()[i];
    std::vector<std::pair<std::string, std::uint64_t>> held;
    for (const auto& [channel, n] : chunk.messages) {
      const auto it = channel_topic_.find(channel);
      held.emplace_back(
          it == channel_topic_.end() || it->second < 0 ? "channel " + std::to_string(channel) : topics_[it->second].name,
          n);
    }
    const std::string what = describeSkippedChunk(chunk.error + "; skipped the chunk", held);
    skipped_.push_back(what);
  }
}

bool McapRecording::next(const std::vector<std::string>& wanted, RecordedMessage& out) {
  RawMessage raw;
  while (cursor_->next(raw)) {
    noteSkips();
    const auto it = channel_topic_.find(raw.channel);
    if (it == channel_topic_.end() || it->second < 0) continue;
    const TopicInfo& t = topics_[it->second];
    if (!wanted.empty() && std::find(wanted.begin(), wanted.end(), t.name) == wanted.end()) continue;
    out.topic = &t;
    out.log_time_ns = raw.log_time_ns;
    out.data = raw.data;
    out.file_offset = raw.offset;
    return true;
  }
  noteSkips();
  return false;
}

}  // namespace

std::unique_ptr<Recording> openMcapRecording(const std::filesystem::path& path) {
  return std::make_unique<McapRecording>(path);
}

}  // namespace cenote::io
