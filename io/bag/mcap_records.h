// mcap_records.h: the record layer of the MCAP reader (mcap_recording.cpp, its only user): the
// little-endian fields of a record, and RecordCursor, which walks the data section front to back,
// opening each chunk (none, zstd, lz4; CRC checked) with one chunk in memory at a time.
// Threads: one cursor per thread.
#pragma once

#include <libdeflate.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "common/error.h"
#include "io/bag/lz4_frame.h"
#include "io/bag/zstd_stream.h"

namespace cenote::io::detail {

inline constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
inline constexpr std::uint64_t kRecordHeader = 9;                        // opcode u8 + content length u64
inline constexpr std::uint64_t kMaxChunkBytes = std::uint64_t{1} << 30;  // compressed or uncompressed

enum Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kDataEnd = 0x0F,
};

inline std::string hex32(std::uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%08x", v);
  return buf;
}

// Thrown by Fields when a record's content is shorter than its fields; turned into an IoError that
// names the file and the record.
struct Malformed {
  std::string what;
};

// Little-endian fields of one record's content (MCAP's strings, byte arrays and maps carry a u32
// length prefix; a chunk's records a u64 one).
class Fields {
 public:
  explicit Fields(std::span<const std::uint8_t> data) : data_(data) {}
  std::uint16_t u16() { return le<std::uint16_t>("u16"); }
  std::uint32_t u32() { return le<std::uint32_t>("u32"); }
  std::uint64_t u64() { return le<std::uint64_t>("u64"); }
  std::string str() {
    const std::span<const std::uint8_t> b = bytes(u32(), "string");
    return std::string(reinterpret_cast<const char*>(b.data()), b.size());
  }
  std::span<const std::uint8_t> bytes(std::uint64_t n, const char* what) {
    if (n > data_.size() - pos_)
      throw Malformed{std::string(what) + " of " + std::to_string(n) + " bytes at byte " + std::to_string(pos_) +
                      " runs past the record's " + std::to_string(data_.size()) + " bytes"};
    const std::span<const std::uint8_t> out = data_.subspan(pos_, n);
    pos_ += n;
    return out;
  }
  std::span<const std::uint8_t> rest() { return bytes(data_.size() - pos_, "rest"); }
  bool atEnd() const { return pos_ >= data_.size(); }

 private:
  template <class T>
  T le(const char* what) {
    const std::span<const std::uint8_t> b = bytes(sizeof(T), what);
    T v = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i) v |= static_cast<T>(T{b[i]} << (8 * i));
    return v;
  }
  std::span<const std::uint8_t> data_;
  std::size_t pos_ = 0;
};

struct RawMessage {
  std::uint16_t channel = 0;
  std::int64_t log_time_ns = 0;
  std::span<const std::uint8_t> data;
  std::uint64_t offset = 0;
};

// Sequential reader of the data section: top-level records, and the records inside each chunk.
// Schema and Channel records go to `on_definition`; next() returns the messages.
class RecordCursor {
 public:
  using DefinitionSink = std::function<void(std::uint8_t opcode, Fields& fields, std::uint64_t offset)>;

  RecordCursor(const std::filesystem::path& path, std::uint64_t file_size, DefinitionSink on_definition)
      : path_(path.string()), file_size_(file_size), in_(path, std::ios::binary), on_definition_(std::move(on_definition)) {
    if (!in_) throwReadError(path_, "cannot open", "MCAP file ");
    pos_ = sizeof kMagic;
  }

  /// The next message of the data section; false at its end (DataEnd, Footer) or at a cut.
  bool next(RawMessage& out) {
    while (true) {
      if (in_chunk_) {
        if (nextInChunk(out)) return true;
        in_chunk_ = false;
        if (!cut_.empty()) return false;
        continue;
      }
      if (done_) return false;
      if (file_size_ - pos_ < kRecordHeader) return stop("cut at byte " + std::to_string(pos_) + ": no footer");
      std::uint8_t head[kRecordHeader];
      readAt(pos_, head, kRecordHeader);
      const std::uint8_t op = head[0];
      std::uint64_t len = 0;
      for (int i = 0; i < 8; ++i) len |= std::uint64_t{head[1 + i]} << (8 * i);
      const std::uint64_t at = pos_;
      const std::uint64_t available = file_size_ - pos_ - kRecordHeader;
      if (op == kFooter || op == kDataEnd) {
        done_ = true;
        return false;
      }
      if (len > available) {
        // A record cut short: only an uncompressed chunk gives up the complete records it holds.
        if (op == kChunk && available <= kMaxChunkBytes) {
          record_.resize(available);
          readAt(at + kRecordHeader, record_.data(), available);
          cut_ = "cut at byte " + std::to_string(file_size_) + " inside the chunk record at byte " + std::to_string(at) +
                 " (" + std::to_string(available) + " of its " + std::to_string(len) + " bytes): no footer";
          done_ = true;
          if (openPartialChunk(at)) continue;
          return false;
        }
        return stop("cut at byte " + std::to_string(file_size_) + " inside the record at byte " + std::to_string(at) +
                    " (" + std::to_string(available) + " of its " + std::to_string(len) + " bytes): no footer");
      }
      pos_ = at + kRecordHeader + len;
      if (op == kMessage || op == kSchema || op == kChannel || op == kChunk) {
        if (len > kMaxChunkBytes)  // a damaged length must not allocate gigabytes
          fail(at, recordName(op) + ": its " + std::to_string(len) + " bytes are more than the 1 GiB this reader holds");
        record_.resize(len);
        readAt(at + kRecordHeader, record_.data(), len);
        Fields fields(record_);
        try {
          if (op == kMessage) {
            parseMessage(fields, at, out);
            return true;
          }
          if (op == kChunk) {
            try {
              openChunk(fields, at);
              in_chunk_ = true;
            } catch (const Malformed& m) {
              skip(at, "chunk: " + m.what);
            }
            continue;
          }
          on_definition_(op, fields, at);
        } catch (const Malformed& m) {
          fail(at, recordName(op) + ": " + m.what);
        }
      }
      // Header, indexes, attachments, metadata and unknown opcodes are stepped over.
    }
  }

  /// Empty when the data section ended properly; otherwise where reading stopped.
  const std::string& cut() const { return cut_; }
  const std::string& path() const { return path_; }
  /// The chunks stepped over, in file order: the error, and the messages per channel the chunk held
  /// (from the Message Index records after it; empty when there are none).
  struct SkippedChunk {
    std::string error;
    std::vector<std::pair<std::uint16_t, std::uint64_t>> messages;
  };
  const std::vector<SkippedChunk>& skipped() const { return skipped_; }

 private:
  static std::string recordName(std::uint8_t op) {
    switch (op) {
      case kSchema: return "schema record";
      case kChannel: return "channel record";
      case kMessage: return "message record";
      case kChunk: return "chunk";
      default: return "record";
    }
  }

  // "chunk: CRC mismatch ..." -> IoError "<path>: chunk at byte 1234: CRC mismatch ...".
  [[noreturn]] void fail(std::uint64_t at, const std::string& what) const {
    throw IoError(path_ + ": " + recordAt(at, what));
  }

  static std::string recordAt(std::uint64_t at, const std::string& what) {
    const std::size_t colon = what.find(':');
    if (colon == std::string::npos) return "record at byte " + std::to_string(at) + ": " + what;
    return what.substr(0, colon) + " at byte " + std::to_string(at) + what.substr(colon);
  }

  bool stop(std::string why) {
    cut_ = std::move(why);
    done_ = true;
    return false;
  }

  void readAt(std::uint64_t at, std::uint8_t* dst, std::uint64_t n) {
    in_.clear();
    in_.seekg(static_cast<std::streamoff>(at));
    in_.read(reinterpret_cast<char*>(dst), static_cast<std::streamsize>(n));
    if (static_cast<std::uint64_t>(in_.gcount()) != n)
      throw IoError(path_ + ": read of " + std::to_string(n) + " bytes at byte " + std::to_string(at) + " failed");
  }

  static void parseMessage(Fields& f, std::uint64_t at, RawMessage& out) {
    out.channel = f.u16();
    f.u32();  // sequence
    out.log_time_ns = static_cast<std::int64_t>(f.u64());
    f.u64();  // publish time
    out.data = f.rest();
    out.offset = at;
  }

  // The fixed fields of a chunk up to its records. Returns the compression and the records' bytes.
  struct ChunkHead {
    std::uint64_t uncompressed_size = 0;
    std::uint32_t crc = 0;
    std::string compression;
  };
  static ChunkHead chunkHead(Fields& f) {
    ChunkHead h;
    f.u64();  // message start time
    f.u64();  // message end time
    h.uncompressed_size = f.u64();
    h.crc = f.u32();
    h.compression = f.str();
    return h;
  }

  void openChunk(Fields& f, std::uint64_t at) {
    const ChunkHead h = chunkHead(f);
    const std::uint64_t records_size = f.u64();
    const std::span<const std::uint8_t> records = f.bytes(records_size, "records");
    chunk_offset_ = at;
    chunk_pos_ = 0;
    if (h.uncompressed_size > kMaxChunkBytes)
      throw Malformed{std::to_string(h.uncompressed_size) +
                      " uncompressed bytes are more than the 1 GiB this reader holds"};
    // chunk_ holds what the records decode to, never the declared size before the data show it: a
    // damaged size field (a gigabyte on a chunk of a hundred bytes) must not allocate it.
    if (h.compression.empty()) {
      if (records.size() != h.uncompressed_size)
        throw Malformed{"uncompressed chunk of " + std::to_string(records.size()) + " bytes declares " +
                        std::to_string(h.uncompressed_size)};
      chunk_.assign(records.begin(), records.end());
    } else if (h.compression == "zstd") {
      try {
        zstdDecompress(records, chunk_, kMaxChunkBytes);
      } catch (const IoError& e) {
        throw Malformed{e.what()};
      }
      if (chunk_.size() != h.uncompressed_size)
        throw Malformed{"zstd gave " + std::to_string(chunk_.size()) + " bytes, the chunk declares " +
                        std::to_string(h.uncompressed_size)};
    } else if (h.compression == "lz4") {
      lz4Frame(records, h.uncompressed_size);
    } else {  // not damage of this chunk: an error, not a skip
      fail(at, "chunk: unknown compression '" + h.compression + "' (this reader reads none, zstd and lz4)");
    }
    if (h.crc != 0) {
      const std::uint32_t crc = static_cast<std::uint32_t>(libdeflate_crc32(0, chunk_.data(), chunk_.size()));
      if (crc != h.crc)
        throw Malformed{"CRC mismatch: the chunk stores " + hex32(h.crc) + ", its " + std::to_string(chunk_.size()) +
                        " uncompressed bytes give " + hex32(crc)};
    }
  }

  // A chunk cut short: its complete inner records when it is uncompressed.
  bool openPartialChunk(std::uint64_t at) {
    Fields f(record_);
    try {
      const ChunkHead h = chunkHead(f);
      f.u64();  // declared records size, past the cut
      if (!h.compression.empty()) return false;
      const std::span<const std::uint8_t> records = f.rest();
      chunk_.assign(records.begin(), records.end());
      chunk_offset_ = at;
      chunk_pos_ = 0;
      partial_chunk_ = true;
      in_chunk_ = true;
      return true;
    } catch (const Malformed&) {
      return false;  // cut inside the chunk's own fields
    }
  }

  // The LZ4 frame `src` into chunk_, grown up to the `declared` size as it decodes (lz4_frame.h, output_growth.h).
  void lz4Frame(std::span<const std::uint8_t> src, std::uint64_t declared) {
    std::string error;
    const bool ended = lz4FrameDecompress(src, declared, declared, chunk_, error);
    if (!error.empty()) throw Malformed{"lz4: " + error};
    if (!ended || chunk_.size() != declared)
      throw Malformed{"lz4 frame gave " + std::to_string(chunk_.size()) + " bytes" + (!ended ? " and is incomplete" : "") +
                      ", the chunk declares " + std::to_string(declared)};
  }

  bool nextInChunk(RawMessage& out) {
    while (chunk_pos_ < chunk_.size()) {
      const std::uint64_t left = chunk_.size() - chunk_pos_;
      std::uint64_t len = 0;
      if (left >= kRecordHeader)
        for (int i = 0; i < 8; ++i) len |= std::uint64_t{chunk_[chunk_pos_ + 1 + i]} << (8 * i);
      if (left < kRecordHeader || len > left - kRecordHeader) {
        if (partial_chunk_) return false;  // the cut; cut_ says so
        return skip(chunk_offset_, "chunk: its record at byte " + std::to_string(chunk_pos_) + " of " +
                                       std::to_string(chunk_.size()) + " uncompressed bytes runs past its end");
      }
      const std::uint8_t op = chunk_[chunk_pos_];
      Fields fields(std::span<const std::uint8_t>(chunk_).subspan(chunk_pos_ + kRecordHeader, len));
      const std::uint64_t inner = chunk_pos_;
      chunk_pos_ += kRecordHeader + len;
      try {
        if (op == kMessage) {
          parseMessage(fields, chunk_offset_, out);
          return true;
        }
        if (op == kSchema || op == kChannel) on_definition_(op, fields, chunk_offset_);
      } catch (const Malformed& m) {
        return skip(chunk_offset_,
                    "chunk: " + recordName(op) + " at byte " + std::to_string(inner) + " of its records: " + m.what);
      }
    }
    return false;
  }

  // A chunk that does not decompress or holds a malformed record: listed in skipped(), with the
  // message counts of the Message Index records that follow it in the file, and stepped over (the
  // rest of it, when some of its messages went out already).
  bool skip(std::uint64_t at, const std::string& what) {
    SkippedChunk s{path_ + ": " + recordAt(at, what), {}};
    std::uint8_t head[kRecordHeader + 6];  // opcode, length, channel id, entries' byte length
    for (std::uint64_t p = pos_; file_size_ - p >= sizeof head;) {
      readAt(p, head, sizeof head);
      if (head[0] != kMessageIndex) break;
      std::uint64_t len = 0;
      for (int i = 0; i < 8; ++i) len |= std::uint64_t{head[1 + i]} << (8 * i);
      if (len < 6 || len > file_size_ - p - kRecordHeader) break;
      std::uint32_t bytes = 0;
      for (int i = 0; i < 4; ++i) bytes |= std::uint32_t{head[kRecordHeader + 2 + i]} << (8 * i);
      const auto channel = static_cast<std::uint16_t>(head[kRecordHeader] | head[kRecordHeader + 1] << 8);
      if (bytes >= 16) s.messages.emplace_back(channel, bytes / 16);
      p += kRecordHeader + len;
    }
    skipped_.push_back(std::move(s));
    chunk_pos_ = chunk_.size();
    return false;
  }

  std::string path_;
  std::uint64_t file_size_;
  std::ifstream in_;
  DefinitionSink on_definition_;
  std::uint64_t pos_ = 0;
  std::vector<std::uint8_t> record_;
  std::vector<std::uint8_t> chunk_;
  std::uint64_t chunk_pos_ = 0;
  std::uint64_t chunk_offset_ = 0;
  bool in_chunk_ = false;
  bool partial_chunk_ = false;
  bool done_ = false;
  std::string cut_;
  std::vector<SkippedChunk> skipped_;
};

}  // namespace cenote::io::detail
