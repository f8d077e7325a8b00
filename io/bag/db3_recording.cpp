#include "io/bag/db3_recording.h"

#include <sqlite3.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdio>
#include <fstream>
#include <limits>
#include <regex>

#include "common/error.h"
#include "io/bag/db3_metadata.h"
#include "io/bag/mcap_recording.h"
#include "io/bag/zstd_stream.h"

namespace cenote::io {
namespace {

namespace fs = std::filesystem;

// Throws NotFoundError when `file` (named `name` in the message) does not exist, IoError with the reason
// when its name cannot even be looked up (a metadata.yaml may list any name, one too long for the file
// system among them: std::filesystem's throwing overloads would throw their own filesystem_error).
void requireFile(const fs::path& file, const std::string& name) {
  std::error_code ec;
  if (fs::exists(file, ec)) return;
  if (ec) throw IoError("cannot read ROS 2 bag file " + name + ": " + ec.message());
  throw NotFoundError("cannot read ROS 2 bag file " + name + ": no such file");
}

// The "file:" URI of `path` that opens it immutable (sqlite's "immutable=1": no locks, no -wal or -shm
// file beside it), its bytes other than letters, digits and "/._-" percent-encoded.
std::string immutableUri(const fs::path& path) {
  std::string uri = "file:";
  for (const unsigned char c : path.string()) {
    if (std::isalnum(c) || c == '/' || c == '.' || c == '_' || c == '-') {
      uri += static_cast<char>(c);
    } else {
      char hex[4];
      std::snprintf(hex, sizeof hex, "%%%02X", c);
      uri += hex;
    }
  }
  return uri + "?immutable=1";
}

// A prepared statement, finalised when it goes: sqlite3_close leaves a connection with a statement
// still open (and its file with it) open.
struct FinalizeStatement {
  void operator()(sqlite3_stmt* stmt) const { sqlite3_finalize(stmt); }
};
using Statement = std::unique_ptr<sqlite3_stmt, FinalizeStatement>;

// Whether the sqlite file at `path` is in WAL mode (its header's read and write versions, bytes 18 and
// 19, are 2), as rosbag2's resilient storage preset writes. False for anything unreadable or shorter:
// the open that follows names the problem.
bool inWalMode(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  char header[20] = {};
  return in.read(header, sizeof header) && header[18] == 2 && header[19] == 2;
}

// Whether a .db3 is read immutable: in WAL mode, sqlite would otherwise make -wal and -shm files beside
// it (beside a bag's own file, in a folder that may be read-only, as a shared dataset often is, where
// the open would fail; beside the decompressed copy of a FILE-compressed one, in the temporary folder,
// where they would outlive the copy). Without a -wal file beside it every message is in the file
// itself; with one, a recorder was killed before its last checkpoint or is still writing, and sqlite
// must read it. A file in rollback-journal mode is read as it is: a reader makes nothing beside it.
bool readImmutable(const fs::path& path) {
  std::error_code ec;
  return inWalMode(path) && !fs::exists(fs::path(path.string() + "-wal"), ec) && !ec;
}

// One .db3 file opened read-only; closes itself.
class Database {
 public:
  // Opens `path`, immutable where readImmutable() says; errors name `name` (the bag's file when `path`
  // is its decompressed copy).
  Database(const fs::path& path, const fs::path& name) : path_(name.string()) {
    requireFile(path, path_);
    const bool immutable = readImmutable(path);
    const std::string file = immutable ? immutableUri(path) : path.string();
    if (sqlite3_open_v2(file.c_str(), &db_, SQLITE_OPEN_READONLY | (immutable ? SQLITE_OPEN_URI : 0), nullptr) !=
        SQLITE_OK) {
      const IoError error = failure("cannot open");
      sqlite3_close(db_);  // sqlite hands out a connection even when the open fails
      throw error;
    }
  }
  ~Database() {
    stmt_.reset();
    sqlite3_close(db_);
  }
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  Statement prepare(const char* sql) {
    sqlite3_stmt* stmt = nullptr;
    if (sqlite3_prepare_v2(db_, sql, -1, &stmt, nullptr) != SQLITE_OK) throw failure("cannot query");
    return Statement(stmt);
  }
  /// SQLITE_ROW or SQLITE_DONE; anything else throws.
  int step(const Statement& stmt) {
    const int rc = sqlite3_step(stmt.get());
    if (rc != SQLITE_ROW && rc != SQLITE_DONE) throw failure("cannot read");
    return rc;
  }
  IoError failure(const char* what) const {
    return IoError("ROS 2 bag file " + path_ + ": " + what + ": " + (db_ ? sqlite3_errmsg(db_) : "out of memory"));
  }
  const std::string& path() const { return path_; }

  Statement stmt_;  // the streaming query of the messages, while it runs

 private:
  std::string path_;
  sqlite3* db_ = nullptr;
};

std::string column(sqlite3_stmt* stmt, int i) {
  const unsigned char* text = sqlite3_column_text(stmt, i);
  return text ? reinterpret_cast<const char*>(text) : "";
}

class Db3Recording final : public Recording {
 public:
  // `topics`: the metadata's topics of a FILE-compressed bag (its files' tables are read as each file
  // is decompressed for reading); otherwise empty, and every file's tables are read now.
  // `sniff_messages`: no metadata says how the bag was compressed, so a message that is a zstd frame
  // is decompressed (compression_mode MESSAGE).
  Db3Recording(std::vector<fs::path> files, std::string truncation, Db3Compression compression = Db3Compression::kNone,
               std::vector<TopicInfo> topics = {}, bool sniff_messages = false)
      : files_(std::move(files)),
        truncation_(std::move(truncation)),
        compression_(compression),
        sniff_messages_(sniff_messages),
        topics_(std::move(topics)) {
    topic_of_id_.resize(files_.size());
    if (compression_ == Db3Compression::kFile) return;  // the topics came from metadata.yaml
    for (std::size_t i = 0; i < files_.size(); ++i) {
      const std::unique_ptr<TempFile> copy = decompressedCopy(files_[i]);
      Database db(copy ? copy->path() : files_[i], files_[i]);
      readTopics(db, i, true);
    }
    const std::vector<int> rank = sortTopicsByName(topics_);
    for (auto& ids : topic_of_id_)
      for (auto& [id, topic] : ids)
        if (topic >= 0) topic = rank[topic];
  }

  const std::vector<TopicInfo>& topics() const override { return topics_; }
  std::string truncation() const override { return truncation_; }
  std::string compression() const override {
    if (compression_ == Db3Compression::kMessage) return "zstd by message (compression_mode MESSAGE)";
    std::error_code ec;
    if (compression_ == Db3Compression::kFile) {
      return "zstd by file (compression_mode FILE): each file is decompressed into " +
             fs::temp_directory_path(ec).string() + " (TMPDIR) while it is read, one at a time";
    }
    return "";
  }

  bool next(const std::vector<std::string>& wanted, RecordedMessage& out) override {
    while (true) {
      if (!db_ && !openNextFile()) return false;
      if (db_->step(db_->stmt_) == SQLITE_DONE) {
        db_.reset();
        copy_.reset();  // the decompressed copy of a FILE-compressed file goes with it
        ++file_index_;
        continue;
      }
      const auto& ids = topic_of_id_[file_index_];
      sqlite3_stmt* row = db_->stmt_.get();
      const auto it = ids.find(sqlite3_column_int64(row, 0));
      if (it == ids.end() || it->second < 0) continue;
      const TopicInfo& topic = topics_[it->second];
      if (!wanted.empty() && std::find(wanted.begin(), wanted.end(), topic.name) == wanted.end()) continue;
      out.topic = &topic;
      out.log_time_ns = sqlite3_column_int64(row, 1);
      const void* blob = sqlite3_column_blob(row, 2);
      const int size = sqlite3_column_bytes(row, 2);
      out.data = std::span<const std::uint8_t>(static_cast<const std::uint8_t*>(blob), static_cast<std::size_t>(size));
      out.file_offset = static_cast<std::uint64_t>(sqlite3_column_int64(row, 3));
      if (compression_ == Db3Compression::kMessage || (sniff_messages_ && isZstd(out.data))) {
        out.data = decompressed(out, topic);
      }
      return true;
    }
  }

 private:
  // Opens files_[file_index_] for its messages (a FILE-compressed one through a decompressed copy in
  // the temporary folder, and its topics table then); false after the last file.
  bool openNextFile() {
    if (file_index_ >= files_.size()) return false;
    const fs::path& file = files_[file_index_];
    copy_ = decompressedCopy(file);
    db_ = std::make_unique<Database>(copy_ ? copy_->path() : file, file);
    if (compression_ == Db3Compression::kFile) readTopics(*db_, file_index_, false);
    db_->stmt_ = db_->prepare("SELECT topic_id, timestamp, data, id FROM messages ORDER BY timestamp, id");
    return true;
  }

  // A FILE-compressed file's (.zstd) decompressed copy in the temporary folder; null for a plain file.
  static std::unique_ptr<TempFile> decompressedCopy(const fs::path& file) {
    if (file.extension() != ".zstd") return nullptr;
    requireFile(file, file.string());
    auto copy = std::make_unique<TempFile>(file.stem().string());
    zstdDecompressFile(file, copy->path());
    return copy;
  }

  // A zstd frame's magic number; a CDR message begins with its encapsulation (00 00, 00 01, ...).
  static bool isZstd(std::span<const std::uint8_t> data) {
    return data.size() >= 4 && data[0] == 0x28 && data[1] == 0xB5 && data[2] == 0x2F && data[3] == 0xFD;
  }

  // The bytes of a MESSAGE-compressed message, valid until the next message.
  std::span<const std::uint8_t> decompressed(const RecordedMessage& m, const TopicInfo& topic) {
    try {
      zstdDecompress(m.data, message_);
    } catch (const IoError& e) {
      throw IoError("ROS 2 bag file " + db_->path() + ": message (row id " + std::to_string(m.file_offset) + ") on " +
                    topic.name + " (compression_mode MESSAGE): " + e.what());
    }
    return message_;
  }

  // The topics table of file `index` into topic_of_id_[index]: a topic not yet known is added (and,
  // when `count`, the messages table's counts and time spans summed) unless topics_ came from the
  // metadata (FILE compression), where a topic it does not list is not read.
  void readTopics(Database& db, std::size_t index, bool count) {
    std::map<std::int64_t, int>& ids = topic_of_id_[index];
    const Statement stmt = db.prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id");
    while (db.step(stmt) == SQLITE_ROW) {
      const std::int64_t id = sqlite3_column_int64(stmt.get(), 0);
      MessageEncoding encoding{};
      if (!db3Encoding(column(stmt.get(), 3), encoding)) {
        ids[id] = -1;
        continue;
      }
      const std::string name = column(stmt.get(), 1);
      const std::string type = ros1TypeName(column(stmt.get(), 2));
      auto same = [&](const TopicInfo& t) { return t.name == name && t.type == type && t.encoding == encoding; };
      const auto found = std::find_if(topics_.begin(), topics_.end(), same);
      if (found != topics_.end()) {
        ids[id] = static_cast<int>(found - topics_.begin());
      } else if (count) {
        topics_.push_back(TopicInfo{name, type, encoding, 0, 0, 0});
        ids[id] = static_cast<int>(topics_.size() - 1);
      } else {
        ids[id] = -1;
      }
    }
    if (count) countMessages(db, ids);
  }

  void countMessages(Database& db, const std::map<std::int64_t, int>& ids) {
    const Statement stmt = db.prepare(
        "SELECT topic_id, COUNT(*), MIN(timestamp), MAX(timestamp) FROM messages GROUP BY topic_id");
    while (db.step(stmt) == SQLITE_ROW) {
      const auto it = ids.find(sqlite3_column_int64(stmt.get(), 0));
      if (it == ids.end() || it->second < 0) continue;
      TopicInfo& t = topics_[it->second];
      const std::int64_t first = sqlite3_column_int64(stmt.get(), 2);
      const std::int64_t last = sqlite3_column_int64(stmt.get(), 3);
      if (t.message_count == 0 || first < t.first_ns) t.first_ns = first;
      if (t.message_count == 0 || last > t.last_ns) t.last_ns = last;
      t.message_count += static_cast<std::uint64_t>(sqlite3_column_int64(stmt.get(), 1));
    }
  }

  std::vector<fs::path> files_;
  std::string truncation_;
  Db3Compression compression_;
  bool sniff_messages_;
  std::vector<TopicInfo> topics_;
  std::vector<std::map<std::int64_t, int>> topic_of_id_;  // per file: topics.id -> index in topics_, -1 not read
  std::size_t file_index_ = 0;
  std::unique_ptr<TempFile> copy_;  // declared before db_: the database closes before its file goes
  std::unique_ptr<Database> db_;
  std::vector<std::uint8_t> message_;  // a MESSAGE-compressed message's bytes
};

// The .db3 (and .db3.zstd) files of a folder without metadata.yaml, by the number before ".db3"
// (dive_2 before dive_10).
std::vector<fs::path> db3FilesIn(const fs::path& folder) {
  std::vector<std::pair<long long, fs::path>> found;
  const std::regex index(R"(_(\d+)\.db3(\.zstd)?$)");
  // The error_code forms: a folder or entry the user may not read is an IoError naming it.
  std::error_code ec;
  fs::directory_iterator entries(folder, ec), end;
  for (; !ec && entries != end; entries.increment(ec)) {
    const fs::directory_entry& e = *entries;
    std::error_code type_ec;
    if (!e.is_regular_file(type_ec) || !isDb3FileName(e.path())) continue;
    std::smatch m;
    const std::string name = e.path().filename().string();
    long long i = -1;
    if (std::regex_search(name, m, index)) {
      // More digits than a long long holds (no recorder writes them) sort after every other file, where
      // std::stoll would throw std::out_of_range.
      const std::string digits = m[1];
      if (std::from_chars(digits.data(), digits.data() + digits.size(), i).ec != std::errc())
        i = std::numeric_limits<long long>::max();
    }
    found.emplace_back(i, e.path());
  }
  if (ec) throw IoError("cannot list ROS 2 bag folder " + folder.string() + ": " + ec.message());
  std::sort(found.begin(), found.end());
  std::vector<fs::path> files;
  for (auto& [i, path] : found) files.push_back(path);
  return files;
}

}  // namespace

bool isDb3FileName(const fs::path& path) {
  const std::string name = path.filename().string();
  auto endsWith = [&](const std::string& suffix) {
    return name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
  };
  return endsWith(".db3") || endsWith(".db3.zstd");
}

std::unique_ptr<Recording> openDb3Recording(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw NotFoundError("cannot read ROS 2 bag " + path.string() + ": no such file or folder");
  if (!fs::is_directory(path, ec)) return std::make_unique<Db3Recording>(std::vector<fs::path>{path}, "");
  if (!fs::exists(path / "metadata.yaml", ec)) {
    std::vector<fs::path> files = db3FilesIn(path);
    if (files.empty())
      throw NotFoundError("cannot read ROS 2 bag " + path.string() + ": no metadata.yaml and no .db3 file in it");
    const auto zstd = std::count_if(files.begin(), files.end(), [](const fs::path& f) { return f.extension() == ".zstd"; });
    const std::string why = "no metadata.yaml (the recorder did not finish): read the " + std::to_string(files.size()) +
                            " .db3 file" + (files.size() == 1 ? "" : "s") + " in the folder" +
                            (zstd > 0 ? " (" + std::to_string(zstd) + " of them .db3.zstd)" : "");
    return std::make_unique<Db3Recording>(std::move(files), why, Db3Compression::kNone, std::vector<TopicInfo>{}, true);
  }
  Db3Metadata metadata = readDb3Metadata(path);
  return std::make_unique<Db3Recording>(std::move(metadata.files), "", metadata.compression, std::move(metadata.topics));
}

}  // namespace cenote::io
