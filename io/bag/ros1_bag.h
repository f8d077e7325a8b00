// ros1_bag.h: a ROS 1 bag (format 2.0, wiki.ros.org/Bags/Format/2.0) read front to back in one pass.
//   #ROSBAG V2.0\n, then records (u32 header length, header of "name=value" fields, u32 data
//   length, data): the bag header (index_pos), chunks of connection and message records (compressed
//   none, bz2 or lz4: roslz4's LZ4 frames) each followed by its index records, and at index_pos the
//   connections and chunk infos.
// Memory: one chunk at a time (the recorder's chunk size, 768 KiB by default, or one larger
// message), whatever the bag's length.
// A bag cut short (the recorder killed: index_pos 0 or past the end, the last chunk partial) is
// scanned when opened (for its topics: the index records after each closed chunk, and the chunks
// that define connections or were cut) and read up to the last complete message;
// truncation() says where it stopped. A complete chunk whose data do not decompress, or whose
// records are malformed, is stepped over: skipped() names it, its offset and the messages it held
// (from the index records after it), and reading goes on with the next chunk. An unknown
// compression or a malformed record outside chunks is an IoError naming the file and the byte offset.
// topics() is complete once the bag is open: a connection of a new topic that a chunk defines later
// (one the index does not list) is not a topic, and its messages are stepped over.
// Threads: one user at a time.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "io/bag/recording.h"

namespace cenote::io {

class Ros1Bag final : public Recording {
 public:
  /// @throws NotFoundError when the file does not exist; IoError when it is not a ROS 1 bag of
  ///         format 2.0 or its index is damaged (the path and byte offset named).
  explicit Ros1Bag(const std::filesystem::path& path);
  ~Ros1Bag() override;
  Ros1Bag(const Ros1Bag&) = delete;
  Ros1Bag& operator=(const Ros1Bag&) = delete;

  const std::vector<TopicInfo>& topics() const override { return topics_; }
  bool next(const std::vector<std::string>& wanted, RecordedMessage& out) override;
  std::string truncation() const override { return truncation_; }
  std::vector<std::string> skipped() const override;

  /// Chunks by compression ("none", "bz2", "lz4"), from the index or the scan.
  const std::map<std::string, std::uint64_t>& chunkCompressions() const { return compressions_; }
  /// Bytes of the file; bytes of the chunks' data as stored and uncompressed (from the index or the scan).
  std::uint64_t fileSize() const { return file_size_; }
  std::uint64_t chunkBytesStored() const { return chunk_stored_; }
  std::uint64_t chunkBytesUncompressed() const { return chunk_uncompressed_; }

 private:
  struct Connection {
    static constexpr std::size_t kNoTopic = static_cast<std::size_t>(-1);
    std::size_t topic = 0;  // index in topics_; kNoTopic: first defined after open, its messages stepped over
  };
  // One record's header fields and where its data lie.
  struct Record {
    std::uint64_t pos = 0;  // of the record in the file (or in the chunk)
    std::uint8_t op = 0;
    std::map<std::string, std::string> fields;
    std::uint64_t data_pos = 0;
    std::uint64_t data_len = 0;
  };

  bool readFileRecord(std::uint64_t pos, Record& record, bool allow_partial);
  void readIndex(std::uint64_t index_pos);
  void scan();
  // The index records after `chunk`: each connection's message count and first and last times.
  // Empty when there are none or one names a connection defined inside the chunk.
  struct IndexEntries {
    std::size_t topic;
    std::int64_t first, last;
    std::uint64_t n;
  };
  std::vector<IndexEntries> indexAfter(const Record& chunk);
  bool countFromIndex(const Record& chunk);
  // Records the damaged `chunk` (once, whichever pass finds it): `damage`, what was `lost` ("the
  // chunk", "the rest of the chunk") and the messages the index says it held.
  void skipChunk(const Record& chunk, const std::string& damage, const std::string& lost);
  void countMessage(std::size_t topic, std::int64_t ns, std::uint64_t n);
  // Reads and decompresses the chunk of `record` into chunk_; false when its data are cut short
  // (chunk_ holds what could be recovered).
  bool loadChunk(const Record& record);
  void addConnection(std::uint32_t conn, const std::string& topic, const std::map<std::string, std::string>& meta,
                     std::uint64_t pos);
  std::string where(std::uint64_t pos) const;
  void readAt(std::uint64_t pos, void* out, std::size_t n);

  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  std::uint64_t file_size_ = 0;
  std::uint64_t index_pos_ = 0;  // 0: no index (scanned)
  std::vector<TopicInfo> topics_;
  std::map<std::uint32_t, Connection> connections_;
  std::map<std::string, std::uint64_t> compressions_;
  std::uint64_t chunk_stored_ = 0, chunk_uncompressed_ = 0;
  std::string truncation_;
  std::map<std::uint64_t, std::string> skipped_;  // damaged chunks stepped over, by offset
  Record chunk_record_;                           // of the current chunk
  std::string stop_;                              // where the scan stopped, the start of truncation_
  bool scanning_ = false;
  bool opened_ = false;  // topics_ is complete: callers hold pointers into it
  std::uint64_t scanned_messages_ = 0;

  // Reading position: the next top-level record, and inside the current chunk.
  std::uint64_t pos_ = 0;
  std::vector<std::uint8_t> chunk_, packed_;
  std::uint64_t chunk_file_pos_ = 0;
  std::size_t chunk_off_ = 0;
  bool in_chunk_ = false;
  bool chunk_cut_ = false;  // the current chunk's data end with the file
  bool done_ = false;
  std::vector<std::string> wanted_;
  std::vector<char> wanted_topics_;  // by topic index
};

}  // namespace cenote::io
