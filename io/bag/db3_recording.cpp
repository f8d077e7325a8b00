#include "io/bag/db3_recording.h"

#include <sqlite3.h>

#include <algorithm>
#include <regex>

#include "common/error.h"
#include "common/yaml_section.h"
#include "io/bag/mcap_recording.h"

namespace cenote::io {
namespace {

namespace fs = std::filesystem;

// One .db3 file opened read-only; closes itself.
class Database {
 public:
  explicit Database(const fs::path& path) : path_(path.string()) {
    if (!fs::exists(path)) throw NotFoundError("cannot read ROS 2 bag file " + path_ + ": no such file");
    if (sqlite3_open_v2(path_.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) fail("cannot open");
  }
  ~Database() {
    if (stmt_) sqlite3_finalize(stmt_);
    sqlite3_close(db_);
  }
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  sqlite3_stmt* prepare(const char* sql) {
    sqlite3_stmt* stmt = nullptr;
    if (sqlite3_prepare_v2(db_, sql, -1, &stmt, nullptr) != SQLITE_OK) fail("cannot query");
    return stmt;
  }
  /// SQLITE_ROW or SQLITE_DONE; anything else throws.
  int step(sqlite3_stmt* stmt) {
    const int rc = sqlite3_step(stmt);
    if (rc != SQLITE_ROW && rc != SQLITE_DONE) fail("cannot read");
    return rc;
  }
  [[noreturn]] void fail(const char* what) const {
    throw IoError("ROS 2 bag file " + path_ + ": " + what + ": " + (db_ ? sqlite3_errmsg(db_) : "out of memory"));
  }
  const std::string& path() const { return path_; }

  sqlite3_stmt* stmt_ = nullptr;  // the streaming query of the messages, while it runs

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
  Db3Recording(std::vector<fs::path> files, std::string truncation)
      : files_(std::move(files)), truncation_(std::move(truncation)) {
    for (const fs::path& file : files_) readTopics(file);
    const std::vector<int> rank = sortTopicsByName(topics_);
    for (auto& ids : topic_of_id_)
      for (auto& [id, topic] : ids)
        if (topic >= 0) topic = rank[topic];
  }

  const std::vector<TopicInfo>& topics() const override { return topics_; }
  std::string truncation() const override { return truncation_; }

  bool next(const std::vector<std::string>& wanted, RecordedMessage& out) override {
    while (true) {
      if (!db_) {
        if (file_index_ >= files_.size()) return false;
        db_ = std::make_unique<Database>(files_[file_index_]);
        db_->stmt_ = db_->prepare("SELECT topic_id, timestamp, data, id FROM messages ORDER BY timestamp, id");
      }
      if (db_->step(db_->stmt_) == SQLITE_DONE) {
        db_.reset();
        ++file_index_;
        continue;
      }
      const auto& ids = topic_of_id_[file_index_];
      const auto it = ids.find(sqlite3_column_int64(db_->stmt_, 0));
      if (it == ids.end() || it->second < 0) continue;
      const TopicInfo& topic = topics_[it->second];
      if (!wanted.empty() && std::find(wanted.begin(), wanted.end(), topic.name) == wanted.end()) continue;
      out.topic = &topic;
      out.log_time_ns = sqlite3_column_int64(db_->stmt_, 1);
      const void* blob = sqlite3_column_blob(db_->stmt_, 2);
      const int size = sqlite3_column_bytes(db_->stmt_, 2);
      out.data = std::span<const std::uint8_t>(static_cast<const std::uint8_t*>(blob), static_cast<std::size_t>(size));
      out.file_offset = static_cast<std::uint64_t>(sqlite3_column_int64(db_->stmt_, 3));
      return true;
    }
  }

 private:
  void readTopics(const fs::path& file) {
    Database db(file);
    std::map<std::int64_t, int>& ids = topic_of_id_.emplace_back();
    sqlite3_stmt* stmt = db.prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id");
    while (db.step(stmt) == SQLITE_ROW) {
      const std::string format = column(stmt, 3);
      const std::int64_t id = sqlite3_column_int64(stmt, 0);
      if (format != "cdr" && format != "ros1") {
        ids[id] = -1;
        continue;
      }
      const std::string name = column(stmt, 1);
      const std::string type = ros1TypeName(column(stmt, 2));
      const MessageEncoding encoding = format == "cdr" ? MessageEncoding::kCdr : MessageEncoding::kRos1;
      auto same = [&](const TopicInfo& t) { return t.name == name && t.type == type && t.encoding == encoding; };
      const auto found = std::find_if(topics_.begin(), topics_.end(), same);
      if (found != topics_.end()) {
        ids[id] = static_cast<int>(found - topics_.begin());
      } else {
        topics_.push_back(TopicInfo{name, type, encoding, 0, 0, 0});
        ids[id] = static_cast<int>(topics_.size() - 1);
      }
    }
    sqlite3_finalize(stmt);
    stmt = db.prepare("SELECT topic_id, COUNT(*), MIN(timestamp), MAX(timestamp) FROM messages GROUP BY topic_id");
    while (db.step(stmt) == SQLITE_ROW) {
      const auto it = ids.find(sqlite3_column_int64(stmt, 0));
      if (it == ids.end() || it->second < 0) continue;
      TopicInfo& t = topics_[it->second];
      const std::int64_t first = sqlite3_column_int64(stmt, 2);
      const std::int64_t last = sqlite3_column_int64(stmt, 3);
      if (t.message_count == 0 || first < t.first_ns) t.first_ns = first;
      if (t.message_count == 0 || last > t.last_ns) t.last_ns = last;
      t.message_count += static_cast<std::uint64_t>(sqlite3_column_int64(stmt, 1));
    }
    sqlite3_finalize(stmt);
  }

  std::vector<fs::path> files_;
  std::string truncation_;
  std::vector<TopicInfo> topics_;
  std::vector<std::map<std::int64_t, int>> topic_of_id_;  // per file: topics.id -> index in topics_, -1 not read
  std::size_t file_index_ = 0;
  std::unique_ptr<Database> db_;
};

// The .db3 files of a folder without metadata.yaml, by the number before ".db3" (dive_2 before dive_10).
std::vector<fs::path> db3FilesIn(const fs::path& folder) {
  std::vector<std::pair<long long, fs::path>> found;
  const std::regex index(R"(_(\d+)\.db3$)");
  for (const fs::directory_entry& e : fs::directory_iterator(folder)) {
    if (!e.is_regular_file() || e.path().extension() != ".db3") continue;
    std::smatch m;
    const std::string name = e.path().filename().string();
    found.emplace_back(std::regex_search(name, m, index) ? std::stoll(m[1]) : -1, e.path());
  }
  std::sort(found.begin(), found.end());
  std::vector<fs::path> files;
  for (auto& [i, path] : found) files.push_back(path);
  return files;
}

}  // namespace

std::unique_ptr<Recording> openDb3Recording(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw NotFoundError("cannot read ROS 2 bag " + path.string() + ": no such file or folder");
  if (!fs::is_directory(path, ec)) return std::make_unique<Db3Recording>(std::vector<fs::path>{path}, "");
  const fs::path metadata = path / "metadata.yaml";
  if (!fs::exists(metadata, ec)) {
    std::vector<fs::path> files = db3FilesIn(path);
    if (files.empty())
      throw NotFoundError("cannot read ROS 2 bag " + path.string() + ": no metadata.yaml and no .db3 file in it");
    const std::string why = "no metadata.yaml (the recorder did not finish): read the " + std::to_string(files.size()) +
                            " .db3 file" + (files.size() == 1 ? "" : "s") + " in the folder";
    return std::make_unique<Db3Recording>(std::move(files), why);
  }
  const YAML::Node root = loadYamlFile(metadata.string());
  const YAML::Node info = root["rosbag2_bagfile_information"];
  const std::string where = metadata.string() + ": rosbag2_bagfile_information";
  if (!info || !info.IsMap()) throw IoError(metadata.string() + ": no rosbag2_bagfile_information mapping");
  try {
    const std::string storage = info["storage_identifier"] ? info["storage_identifier"].as<std::string>() : "sqlite3";
    if (storage != "sqlite3")
      throw IoError(where + ".storage_identifier is '" + storage +
                    "'; this reader reads sqlite3 (open an mcap "
                    "bag's .mcap file itself)");
    const std::string compression = info["compression_mode"] ? info["compression_mode"].as<std::string>() : "";
    if (!compression.empty() && compression != "NONE")
      throw IoError(where + ".compression_mode is '" + compression +
                    "': compressed bags are not read; convert it first (ros2 bag convert)");
    const YAML::Node paths = info["relative_file_paths"];
    if (!paths || !paths.IsSequence() || paths.size() == 0)
      throw IoError(where + ".relative_file_paths: expected a non-empty list of .db3 files");
    std::vector<fs::path> files;
    for (const YAML::Node& p : paths) files.push_back(path / p.as<std::string>());
    return std::make_unique<Db3Recording>(std::move(files), "");
  } catch (const YAML::Exception& e) {
    throw IoError(where + ": " + e.what());
  }
}

}  // namespace cenote::io
