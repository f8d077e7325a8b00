#include "io/bag/ros1_bag.h"

#include <bzlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <limits>

#include "common/error.h"
#include "io/bag/lz4_frame.h"
#include "io/bag/output_growth.h"

namespace cenote::io {
namespace {

constexpr char kMagic[] = "#ROSBAG V2.0\n";
constexpr std::size_t kMagicLen = sizeof(kMagic) - 1;
constexpr std::uint8_t kOpMessage = 0x02, kOpBagHeader = 0x03, kOpIndex = 0x04, kOpChunk = 0x05, kOpChunkInfo = 0x06,
                       kOpConnection = 0x07;
// A chunk's uncompressed size above this is damage, not a recording (rosbag writes 768 KiB chunks, or
// one message if it is larger; no ROS message is 1 GiB).
constexpr std::uint64_t kMaxChunkBytes = std::uint64_t{1} << 30;

template <class T>
T loadLe(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

// "name=value" fields, each prefixed by its u32 length. @throws IoError (what names the record).
std::map<std::string, std::string> parseFields(const std::uint8_t* p, std::size_t n, const std::string& what) {
  std::map<std::string, std::string> fields;
  std::size_t i = 0;
  while (i < n) {
    if (n - i < 4) throw IoError(what + ": header field length cut short");
    const std::uint32_t len = loadLe<std::uint32_t>(p + i);
    i += 4;
    if (len > n - i) throw IoError(what + ": header field of " + std::to_string(len) + " bytes runs past the header");
    const char* f = reinterpret_cast<const char*>(p + i);
    const char* eq = static_cast<const char*>(std::memchr(f, '=', len));
    if (eq == nullptr) throw IoError(what + ": header field without '='");
    fields.emplace(std::string(f, eq), std::string(eq + 1, f + len));
    i += len;
  }
  return fields;
}

template <class T>
T field(const std::map<std::string, std::string>& fields, const char* name, const std::string& what) {
  const auto it = fields.find(name);
  if (it == fields.end() || it->second.size() != sizeof(T)) {
    throw IoError(what + ": header field '" + name + "' missing or not " + std::to_string(sizeof(T)) + " bytes");
  }
  return loadLe<T>(reinterpret_cast<const std::uint8_t*>(it->second.data()));
}

std::string textField(const std::map<std::string, std::string>& fields, const char* name, const std::string& what) {
  const auto it = fields.find(name);
  if (it == fields.end()) throw IoError(what + ": header field '" + name + "' missing");
  return it->second;
}

void checkCompression(const std::string& compression, const std::string& what) {
  if (compression != "none" && compression != "bz2" && compression != "lz4") {
    throw IoError(what + ": unknown compression '" + compression + "' (a ROS 1 bag's chunks are none, bz2 or lz4)");
  }
}

std::int64_t timeNs(std::uint64_t packed) {
  return static_cast<std::int64_t>(packed & 0xffffffffu) * 1000000000 + static_cast<std::int64_t>(packed >> 32);
}

// Appends the decompressed `in` to `out`; false when the data end before the stream does (a cut
// chunk: `out` holds what was recovered). @throws IoError with `what` for corrupt data.
bool inflateBz2(const std::vector<std::uint8_t>& in, std::uint64_t expected, std::vector<std::uint8_t>& out,
                const std::string& what) {
  bz_stream s{};
  if (BZ2_bzDecompressInit(&s, 0, 0) != BZ_OK) throw IoError(what + ": bz2 decoder failed to start");
  // Sized as output_growth.h says: a damaged size field allocates nothing before the data show it.
  out.resize(detail::initialOutputBytes(expected, in.size(), kMaxChunkBytes));
  s.next_in = const_cast<char*>(reinterpret_cast<const char*>(in.data()));
  s.avail_in = static_cast<unsigned>(in.size());
  std::size_t produced = 0;
  int rc = BZ_OK;
  while (true) {
    if (produced == out.size()) {
      if (out.size() >= kMaxChunkBytes) break;
      out.resize(detail::grownOutputBytes(out.size(), kMaxChunkBytes));
    }
    s.next_out = reinterpret_cast<char*>(out.data() + produced);
    s.avail_out = static_cast<unsigned>(out.size() - produced);
    rc = BZ2_bzDecompress(&s);
    produced = out.size() - s.avail_out;
    if (rc != BZ_OK) break;
    if (s.avail_in == 0 && s.avail_out > 0) break;  // input used up before the end of the stream
  }
  BZ2_bzDecompressEnd(&s);
  out.resize(produced);
  if (rc == BZ_STREAM_END) return true;
  if (rc != BZ_OK) {
    if (rc == BZ_DATA_ERROR || rc == BZ_DATA_ERROR_MAGIC) return false;  // the caller decides: cut or corrupt
    throw IoError(what + ": bz2 decoding failed (code " + std::to_string(rc) + ")");
  }
  return false;
}

// The same for an LZ4 frame: false for corrupt data too (the caller decides: cut or corrupt).
bool inflateLz4(const std::vector<std::uint8_t>& in, std::uint64_t expected, std::vector<std::uint8_t>& out) {
  std::string error;
  return detail::lz4FrameDecompress(in, expected, kMaxChunkBytes, out, error);
}

}  // namespace

Ros1Bag::Ros1Bag(const std::filesystem::path& path) : path_(path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw NotFoundError("cannot read bag " + path.string() + ": no such file");
  file_ = std::fopen(path.c_str(), "rb");
  if (file_ == nullptr) throwReadError(path.string(), std::strerror(errno), "bag ");
  file_size_ = std::filesystem::file_size(path, ec);
  char magic[kMagicLen] = {};
  if (file_size_ < kMagicLen || std::fread(magic, 1, kMagicLen, file_) != kMagicLen ||
      std::memcmp(magic, kMagic, kMagicLen) != 0) {
    std::fclose(file_);
    file_ = nullptr;
    const bool v12 = std::memcmp(magic, "#ROSBAG V1.2", 12) == 0;
    throw IoError("bag " + path.string() + ": " +
                  (v12 ? "ROS bag format 1.2 is not read (rosbag fix converts it to 2.0)"
                       : "not a ROS 1 bag (format 2.0 starts with '#ROSBAG V2.0')"));
  }
  try {
    Record header;
    if (!readFileRecord(kMagicLen, header, true) || header.op != kOpBagHeader) {
      throw IoError(where(kMagicLen) + ": no bag header record");
    }
    const std::uint64_t index_pos = field<std::uint64_t>(header.fields, "index_pos", where(kMagicLen));
    pos_ = header.data_pos + header.data_len;
    const std::uint64_t first_record = pos_;
    if (index_pos >= first_record && index_pos < file_size_) {
      readIndex(index_pos);
    }
    if (index_pos_ == 0) scan();
    pos_ = first_record;
    opened_ = true;
  } catch (...) {
    std::fclose(file_);
    file_ = nullptr;
    throw;
  }
}

Ros1Bag::~Ros1Bag() {
  if (file_ != nullptr) std::fclose(file_);
}

std::string Ros1Bag::where(std::uint64_t pos) const { return "bag " + path_.string() + ", byte " + std::to_string(pos); }

void Ros1Bag::readAt(std::uint64_t pos, void* out, std::size_t n) {
  if (fseeko(file_, static_cast<off_t>(pos), SEEK_SET) != 0 || std::fread(out, 1, n, file_) != n) {
    throw IoError(where(pos) + ": read of " + std::to_string(n) + " bytes failed");
  }
}

bool Ros1Bag::readFileRecord(std::uint64_t pos, Record& record, bool allow_partial) {
  record = Record{};
  record.pos = pos;
  const std::uint64_t left = file_size_ > pos ? file_size_ - pos : 0;
  std::uint8_t len4[4];
  if (left < 4) {
    if (allow_partial) return false;
    throw IoError(where(pos) + ": record cut short");
  }
  readAt(pos, len4, 4);
  const std::uint32_t header_len = loadLe<std::uint32_t>(len4);
  if (header_len > left - 4 || left - 4 - header_len < 4) {
    if (allow_partial) return false;
    throw IoError(where(pos) + ": record header of " + std::to_string(header_len) + " bytes runs past the file");
  }
  std::vector<std::uint8_t> header(header_len + 4);
  readAt(pos + 4, header.data(), header.size());
  record.fields = parseFields(header.data(), header_len, where(pos));
  record.op = field<std::uint8_t>(record.fields, "op", where(pos));
  record.data_len = loadLe<std::uint32_t>(header.data() + header_len);
  record.data_pos = pos + 8 + header_len;
  return true;
}

void Ros1Bag::addConnection(std::uint32_t conn, const std::string& topic, const std::map<std::string, std::string>& meta,
                            std::uint64_t pos) {
  if (connections_.count(conn)) return;
  const auto it = std::find_if(topics_.begin(), topics_.end(), [&](const TopicInfo& t) { return t.name == topic; });
  std::size_t index = static_cast<std::size_t>(it - topics_.begin());
  if (it == topics_.end() && opened_) {  // a new topic now would move the topics callers point to
    connections_[conn].topic = Connection::kNoTopic;
    return;
  }
  if (it == topics_.end()) {
    TopicInfo info;
    info.name = topic;
    info.type = textField(meta, "type", where(pos) + " (connection of " + topic + ")");
    info.encoding = MessageEncoding::kRos1;
    topics_.push_back(info);
  }
  connections_[conn].topic = index;
}

void Ros1Bag::readIndex(std::uint64_t index_pos) {
  std::vector<std::uint64_t> chunk_positions;
  std::vector<std::uint8_t> data;
  for (std::uint64_t pos = index_pos; pos < file_size_;) {
    Record r;
    if (!readFileRecord(pos, r, true) || r.data_pos + r.data_len > file_size_) return;  // cut: scan instead
    data.resize(r.data_len);
    readAt(r.data_pos, data.data(), data.size());
    if (r.op == kOpConnection) {
      const std::uint32_t conn = field<std::uint32_t>(r.fields, "conn", where(pos));
      addConnection(conn, textField(r.fields, "topic", where(pos)), parseFields(data.data(), data.size(), where(pos)), pos);
    } else if (r.op == kOpChunkInfo) {
      chunk_positions.push_back(field<std::uint64_t>(r.fields, "chunk_pos", where(pos)));
      const std::uint32_t n = field<std::uint32_t>(r.fields, "count", where(pos));
      if (data.size() < std::size_t{n} * 8) throw IoError(where(pos) + ": chunk info shorter than its count");
      for (std::uint32_t i = 0; i < n; ++i) {
        const auto c = connections_.find(loadLe<std::uint32_t>(data.data() + 8 * i));
        if (c == connections_.end()) throw IoError(where(pos) + ": chunk info names an unknown connection");
        topics_[c->second.topic].message_count += loadLe<std::uint32_t>(data.data() + 8 * i + 4);
      }
    }
    pos = r.data_pos + r.data_len;
  }
  // The index records after each chunk: each connection's message times.
  std::vector<bool> seen(topics_.size(), false);
  for (const std::uint64_t chunk_pos : chunk_positions) {
    Record chunk;
    if (!readFileRecord(chunk_pos, chunk, false) || chunk.op != kOpChunk) {
      throw IoError(where(chunk_pos) + ": the index names a chunk here, but there is none");
    }
    const std::string compression = textField(chunk.fields, "compression", where(chunk_pos));
    checkCompression(compression, where(chunk_pos) + " (chunk)");
    ++compressions_[compression];
    chunk_stored_ += chunk.data_len;
    chunk_uncompressed_ += field<std::uint32_t>(chunk.fields, "size", where(chunk_pos));
    for (std::uint64_t pos = chunk.data_pos + chunk.data_len; pos < index_pos;) {
      Record r;
      if (!readFileRecord(pos, r, false) || r.op != kOpIndex) break;
      const auto c = connections_.find(field<std::uint32_t>(r.fields, "conn", where(pos)));
      if (c == connections_.end()) throw IoError(where(pos) + ": index names an unknown connection");
      if (r.data_len > file_size_ - r.data_pos) {  // before the buffer: a damaged length is up to 4 GiB
        throw IoError(where(pos) + ": record data of " + std::to_string(r.data_len) + " bytes runs past the file");
      }
      data.resize(r.data_len);
      readAt(r.data_pos, data.data(), data.size());
      TopicInfo& t = topics_[c->second.topic];
      for (std::size_t i = 0; i + 12 <= data.size(); i += 12) {
        const std::int64_t ns = timeNs(loadLe<std::uint64_t>(data.data() + i));
        if (!seen[c->second.topic] || ns < t.first_ns) t.first_ns = ns;
        if (!seen[c->second.topic] || ns > t.last_ns) t.last_ns = ns;
        seen[c->second.topic] = true;
      }
      pos = r.data_pos + r.data_len;
    }
  }
  index_pos_ = index_pos;
}

void Ros1Bag::countMessage(std::size_t topic, std::int64_t ns, std::uint64_t n) {
  TopicInfo& t = topics_[topic];
  if (t.message_count == 0 || ns < t.first_ns) t.first_ns = ns;
  if (t.message_count == 0 || ns > t.last_ns) t.last_ns = ns;
  t.message_count += n;
  scanned_messages_ += n;
}

std::vector<Ros1Bag::IndexEntries> Ros1Bag::indexAfter(const Record& chunk) {
  // The index records rosbag writes after each chunk it closes: each connection's message times.
  std::vector<IndexEntries> entries;
  std::vector<std::uint8_t> data;
  for (std::uint64_t pos = chunk.data_pos + chunk.data_len; pos < file_size_;) {
    Record r;
    if (!readFileRecord(pos, r, true) || r.op != kOpIndex || r.data_pos + r.data_len > file_size_) break;
    const auto c = connections_.find(field<std::uint32_t>(r.fields, "conn", where(pos)));
    if (c == connections_.end()) return {};  // a connection first defined inside this chunk
    if (c->second.topic == Connection::kNoTopic) {
      pos = r.data_pos + r.data_len;
      continue;
    }
    data.resize(r.data_len);
    readAt(r.data_pos, data.data(), data.size());
    IndexEntries e{c->second.topic, 0, 0, 0};
    for (std::size_t i = 0; i + 12 <= data.size(); i += 12, ++e.n) {
      const std::int64_t ns = timeNs(loadLe<std::uint64_t>(data.data() + i));
      e.first = e.n == 0 ? ns : std::min(e.first, ns);
      e.last = e.n == 0 ? ns : std::max(e.last, ns);
    }
    if (e.n > 0) entries.push_back(e);
    pos = r.data_pos + r.data_len;
  }
  return entries;
}

bool Ros1Bag::countFromIndex(const Record& chunk) {
  const std::vector<IndexEntries> entries = indexAfter(chunk);
  if (entries.empty()) return false;
  for (const IndexEntries& e : entries) {
    countMessage(e.topic, e.first, 0);
    countMessage(e.topic, e.last, e.n);
  }
  ++compressions_[textField(chunk.fields, "compression", where(chunk.pos))];
  chunk_stored_ += chunk.data_len;
  chunk_uncompressed_ += field<std::uint32_t>(chunk.fields, "size", where(chunk.pos));
  return true;
}

void Ros1Bag::skipChunk(const Record& chunk, const std::string& damage, const std::string& lost) {
  if (skipped_.count(chunk.pos) != 0) return;
  std::vector<std::pair<std::string, std::uint64_t>> held;
  for (const IndexEntries& e : indexAfter(chunk)) held.emplace_back(topics_[e.topic].name, e.n);
  const std::string what = describeSkippedChunk(damage + "; skipped " + lost, held);
  skipped_[chunk.pos] = what;
}

std::vector<std::string> Ros1Bag::skipped() const {
  std::vector<std::string> out;
  for (const auto& [pos, what] : skipped_) out.push_back(what);
  return out;
}

void Ros1Bag::scan() {
  // One pass over the bag, counting what is there: a chunk rosbag closed is counted from the index
  // records after it (no decompression) once its connections are known; the others (the first
  // chunks, which define the connections, and the one cut short) are read. The real pass then
  // starts again from the top.
  scanning_ = true;
  RecordedMessage m;
  while (next({}, m)) countMessage(static_cast<std::size_t>(m.topic - topics_.data()), m.log_time_ns, 1);
  scanning_ = false;
  truncation_ = stop_ + "no index; " + std::to_string(scanned_messages_) + " complete messages read";
  in_chunk_ = false;
  done_ = false;
  chunk_.clear();
  packed_.clear();
  wanted_.clear();
  wanted_topics_.clear();
}

bool Ros1Bag::loadChunk(const Record& r) {
  const std::string what = where(r.pos) + " (chunk)";
  const std::string compression = textField(r.fields, "compression", what);
  const std::uint32_t size = field<std::uint32_t>(r.fields, "size", what);
  checkCompression(compression, what);
  // A chunk being written when the recorder stopped has a data length of 0 (rosbag fills it in when
  // the chunk closes) or one past the end of the file.
  const std::uint64_t available = file_size_ - std::min(file_size_, r.data_pos);
  const bool cut = (r.data_len == 0 && size == 0) || r.data_len > available;
  const std::uint64_t stored = cut ? available : r.data_len;
  if (!cut && size > kMaxChunkBytes) {
    throw IoError(what + ": uncompressed size " + std::to_string(size) + " bytes exceeds " +
                  std::to_string(kMaxChunkBytes));
  }
  if (index_pos_ == 0) {
    ++compressions_[compression];
    chunk_stored_ += stored;
  }
  if (compression == "none") {
    chunk_.resize(stored);
    if (stored > 0) readAt(r.data_pos, chunk_.data(), stored);
    if (!cut && size != stored) {
      throw IoError(what + ": uncompressed chunk of " + std::to_string(stored) + " bytes says its size is " +
                    std::to_string(size));
    }
  } else {
    packed_.resize(stored);
    if (stored > 0) readAt(r.data_pos, packed_.data(), stored);
    const bool whole = compression == "bz2" ? inflateBz2(packed_, cut ? 0 : size, chunk_, what)
                                            : inflateLz4(packed_, cut ? 0 : size, chunk_);
    if (!cut && (!whole || chunk_.size() != size)) {
      throw IoError(what + ": " + compression + " data are corrupt (" + std::to_string(chunk_.size()) + " of " +
                    std::to_string(size) + " bytes decoded)");
    }
  }
  if (index_pos_ == 0) chunk_uncompressed_ += chunk_.size();
  return !cut;
}

bool Ros1Bag::next(const std::vector<std::string>& wanted, RecordedMessage& out) {
  if (wanted != wanted_ || wanted_topics_.size() != topics_.size()) {
    wanted_ = wanted;
    wanted_topics_.assign(topics_.size(), wanted.empty() ? 1 : 0);
    for (std::size_t i = 0; i < topics_.size(); ++i) {
      if (std::find(wanted.begin(), wanted.end(), topics_[i].name) != wanted.end()) wanted_topics_[i] = 1;
    }
  }
  while (!done_) {
    if (in_chunk_) {
      const std::size_t left = chunk_.size() - chunk_off_;
      const std::uint8_t* p = chunk_.data() + chunk_off_;
      if (left == 0) {
        in_chunk_ = false;
        if (chunk_cut_) {
          stop_ = "cut at byte " + std::to_string(file_size_) + ", inside the chunk at byte " +
                  std::to_string(chunk_file_pos_) + ": ";
          break;
        }
        continue;
      }
      try {
        const std::string what = where(chunk_file_pos_) + " (chunk), record at byte " + std::to_string(chunk_off_) +
                                 " of its " + std::to_string(chunk_.size());
        std::uint32_t header_len = left >= 4 ? loadLe<std::uint32_t>(p) : 0;
        if (left < 8 || header_len > left - 8 || loadLe<std::uint32_t>(p + 4 + header_len) > left - 8 - header_len) {
          if (!chunk_cut_) throw IoError(what + ": record runs past the end of the chunk");
          stop_ = "cut at byte " + std::to_string(file_size_) + ", inside the chunk at byte " +
                  std::to_string(chunk_file_pos_) + ": ";
          break;
        }
        const std::map<std::string, std::string> fields = parseFields(p + 4, header_len, what);
        const std::uint32_t data_len = loadLe<std::uint32_t>(p + 4 + header_len);
        const std::uint8_t* data = p + 8 + header_len;
        chunk_off_ += 8 + header_len + data_len;
        const std::uint8_t op = field<std::uint8_t>(fields, "op", what);
        if (op == kOpConnection) {
          addConnection(field<std::uint32_t>(fields, "conn", what), textField(fields, "topic", what),
                        parseFields(data, data_len, what), chunk_file_pos_);
          if (wanted_topics_.size() != topics_.size()) wanted_topics_.resize(topics_.size(), wanted_.empty() ? 1 : 0);
        } else if (op == kOpMessage) {
          const auto c = connections_.find(field<std::uint32_t>(fields, "conn", what));
          if (c == connections_.end()) throw IoError(what + ": message of a connection the bag never defines");
          if (c->second.topic == Connection::kNoTopic || !wanted_topics_[c->second.topic]) continue;
          out.topic = &topics_[c->second.topic];
          out.log_time_ns = timeNs(field<std::uint64_t>(fields, "time", what));
          out.data = std::span<const std::uint8_t>(data, data_len);
          out.file_offset = chunk_file_pos_;
          return true;
        }
      } catch (const IoError& damage) {
        // Malformed records in a whole chunk: its other messages are lost, the bag's are not.
        if (chunk_cut_) throw;
        skipChunk(chunk_record_, damage.what(), "the rest of the chunk");
        in_chunk_ = false;
      }
      continue;
    }
    if (index_pos_ != 0 && pos_ >= index_pos_) break;
    Record r;
    if (!readFileRecord(pos_, r, index_pos_ == 0)) {
      stop_ = pos_ >= file_size_ ? "ends at byte " + std::to_string(file_size_) + " after a whole record: "
                                 : "cut at byte " + std::to_string(file_size_) + ", inside the record at byte " +
                                       std::to_string(pos_) + ": ";
      break;
    }
    if (r.op == kOpChunk) {
      const bool whole = !(r.data_len == 0 && field<std::uint32_t>(r.fields, "size", where(r.pos)) == 0) &&
                         r.data_pos + r.data_len <= file_size_;
      if (scanning_ && whole && countFromIndex(r)) {
        checkCompression(textField(r.fields, "compression", where(r.pos)), where(r.pos) + " (chunk)");
        pos_ = r.data_pos + r.data_len;
        continue;
      }
      // An unknown compression is the whole bag's problem, not one chunk's: it stays an error.
      const auto compression = r.fields.find("compression");
      if (compression != r.fields.end()) checkCompression(compression->second, where(r.pos) + " (chunk)");
      try {
        chunk_cut_ = !loadChunk(r);
      } catch (const IoError& damage) {
        skipChunk(r, damage.what(), "the chunk");
        pos_ = r.data_pos + r.data_len;
        continue;
      }
      chunk_record_ = r;
      chunk_file_pos_ = r.pos;
      chunk_off_ = 0;
      in_chunk_ = true;
      pos_ = chunk_cut_ ? file_size_ : r.data_pos + r.data_len;
      continue;
    }
    if (r.op == kOpConnection && index_pos_ == 0 && r.data_pos + r.data_len <= file_size_) {
      std::vector<std::uint8_t> data(r.data_len);
      readAt(r.data_pos, data.data(), data.size());
      addConnection(field<std::uint32_t>(r.fields, "conn", where(r.pos)), textField(r.fields, "topic", where(r.pos)),
                    parseFields(data.data(), data.size(), where(r.pos)), r.pos);
    } else if (r.op != kOpIndex && r.op != kOpChunkInfo && r.op != kOpConnection && r.op != kOpBagHeader) {
      throw IoError(where(r.pos) + ": record of unknown op " + std::to_string(r.op));
    }
    pos_ = r.data_pos + r.data_len;
  }
  done_ = true;
  return false;
}

}  // namespace cenote::io
