// ROS 2 sqlite3 bags written by Python's sqlite3 in rosbag2's tables (tests/io/bag/gen/gen_db3.py) with
// the CDR bytes of Foxglove's serialiser: topics, counts, time spans and every message's bytes in
// timestamp order across the bag's two files; a bag whose recorder never wrote metadata.yaml; the same
// bag with rosbag2's zstd compression (python3-zstandard) of each message and of each file; bags in
// WAL mode (rosbag2's resilient preset), read without files made beside them, and from their -wal
// files where a recorder was killed before a checkpoint; the errors for a file that is not a database
// or is damaged inside, a missing bag, damaged or unknown compression.
#include "io/bag/db3_recording.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <limits>
#include <optional>
#include <nlohmann/json.hpp>

#include "common/error.h"
#include "tests/io/bag/ros2_test_data.h"
#include "tests/support/scratch_dir.h"

namespace cenote::io::test {
namespace {

namespace fs = std::filesystem;

void expectMessages(Recording& rec, const nlohmann::json& want, const std::vector<std::string>& wanted) {
  RecordedMessage m;
  std::size_t i = 0;
  for (const auto& w : want) {
    if (!wanted.empty() && std::find(wanted.begin(), wanted.end(), w["topic"].get<std::string>()) == wanted.end()) continue;
    ASSERT_TRUE(rec.next(wanted, m)) << "message " << i << " missing";
    EXPECT_EQ(m.topic->name, w["topic"]) << "message " << i;
    EXPECT_EQ(m.log_time_ns, std::stoll(w["log_time_ns"].get<std::string>())) << "message " << i;
    EXPECT_EQ(Bytes(m.data.begin(), m.data.end()), fromHex(w["data"])) << "message " << i;
    ++i;
  }
  EXPECT_FALSE(rec.next(wanted, m)) << "more messages than written after " << i;
}

// The bag kData/name: expected.json's topics and every message's bytes, with these truncation and
// compression lines.
void expectBag(const std::string& name, const std::string& truncation, const std::string& compression) {
  const nlohmann::json want = expectedJson();
  const std::unique_ptr<Recording> rec = openDb3Recording(kData / name);
  expectTopics(*rec, want["topics"]);
  EXPECT_EQ(rec->truncation(), truncation);
  EXPECT_EQ(rec->compression(), compression);
  expectMessages(*rec, want["messages"], {});
}

TEST(Db3Recording, TopicsCountsAndTimeSpansOfBothFiles) {
  const nlohmann::json want = expectedJson();
  const std::unique_ptr<Recording> rec = openDb3Recording(kData / "dive_db3");
  expectTopics(*rec, want["topics"]);
  EXPECT_EQ(rec->truncation(), "");
}

TEST(Db3Recording, EveryMessageInTimestampOrderWithItsBytes) {
  const nlohmann::json want = expectedJson();
  ASSERT_EQ(want["messages"].size(), 34u);
  const std::unique_ptr<Recording> rec = openDb3Recording(kData / "dive_db3");
  expectMessages(*rec, want["messages"], {});
}

TEST(Db3Recording, OnlyTheWantedTopics) {
  const nlohmann::json want = expectedJson();
  const std::unique_ptr<Recording> rec = openDb3Recording(kData / "dive_db3");
  expectMessages(*rec, want["messages"], {"/cam1/image_raw", "/odom"});
}

TEST(Db3Recording, ABagWithoutMetadataIsReadFromItsFilesAndSaysSo) {
  expectBag("dive_db3_cut", "no metadata.yaml (the recorder did not finish): read the 2 .db3 files in the folder", "");
}

// The files of a folder without metadata.yaml come in the order of their index numbers; one with more
// digits than a long long holds comes after the others.
TEST(Db3Recording, FileIndexBeyondALongLongIsReadLast) {
  const fs::path bag = fs::path(::testing::TempDir()) / "huge_index";
  fs::remove_all(bag);
  fs::create_directories(bag);
  fs::copy_file(kData / "dive_db3_cut" / "dive_db3_1.db3", bag / "dive_db3_99999999999999999999.db3");
  fs::copy_file(kData / "dive_db3_cut" / "dive_db3_0.db3", bag / "dive_db3_0.db3");
  const std::unique_ptr<Recording> rec = openDb3Recording(bag);
  EXPECT_EQ(rec->truncation(), "no metadata.yaml (the recorder did not finish): read the 2 .db3 files in the folder");
  expectMessages(*rec, expectedJson()["messages"], {});
}

TEST(Db3Recording, OneDb3FileOnItsOwn) {
  const nlohmann::json want = expectedJson();
  const std::unique_ptr<Recording> rec = openDb3Recording(kData / "dive_db3" / "dive_db3_0.db3");
  nlohmann::json first_half = nlohmann::json::array();
  for (std::size_t i = 0; i < 17; ++i) first_half.push_back(want["messages"][i]);
  expectMessages(*rec, first_half, {});
}

TEST(Db3Recording, NotADatabaseNamesTheFile) {
  const fs::path path = kData / "not_a_database.db3";
  try {
    openDb3Recording(path);
    FAIL() << "expected an IoError";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()), "ROS 2 bag file " + path.string() + ": cannot query: file is not a database");
  }
}

// Damage sqlite finds only when a query reads the page (malformed.db3: the messages table's root page)
// names the file, and leaves neither the file nor its connection open.
TEST(Db3Recording, MalformedDatabaseNamesTheFileAndLeavesItClosed) {
  const fs::path path = kData / "malformed.db3";
  const auto open_files = [] { return std::distance(fs::directory_iterator("/proc/self/fd"), fs::directory_iterator()); };
  const auto before = open_files();
  for (int i = 0; i < 3; ++i) {
    try {
      openDb3Recording(path);
      FAIL() << "expected an IoError";
    } catch (const IoError& e) {
      EXPECT_EQ(std::string(e.what()),
                "ROS 2 bag file " + path.string() + ": cannot read: database disk image is malformed");
    }
  }
  EXPECT_EQ(open_files(), before);
}

TEST(Db3Recording, MissingBagAndMissingListedFile) {
  try {
    openDb3Recording(kData / "absent_bag");
    FAIL() << "expected a NotFoundError";
  } catch (const NotFoundError& e) {
    EXPECT_EQ(std::string(e.what()),
              "cannot read ROS 2 bag " + (kData / "absent_bag").string() + ": no such file or folder");
  }
  const fs::path bag = fs::path(::testing::TempDir()) / "listed_file_missing";
  fs::create_directories(bag);
  std::ofstream(bag / "metadata.yaml") << "rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n"
                                          "  relative_file_paths: [gone_0.db3]\n";
  try {
    openDb3Recording(bag);
    FAIL() << "expected a NotFoundError";
  } catch (const NotFoundError& e) {
    EXPECT_EQ(std::string(e.what()), "cannot read ROS 2 bag file " + (bag / "gone_0.db3").string() + ": no such file");
  }
}

TEST(Db3Recording, MessageCompressedBagGivesEveryMessagesBytes) {
  expectBag("dive_db3_message", "", "zstd by message (compression_mode MESSAGE)");
}

// A folder of its own as TMPDIR for the test's lifetime, to see the decompressed copies come and go.
class TempDirScope {
 public:
  explicit TempDirScope(const std::string& name) : dir_(fs::path(::testing::TempDir()) / name) {
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    const char* old = std::getenv("TMPDIR");
    if (old) old_ = old;
    setenv("TMPDIR", dir_.c_str(), 1);
  }
  ~TempDirScope() {
    if (old_) setenv("TMPDIR", old_->c_str(), 1);
    else unsetenv("TMPDIR");
  }
  const fs::path& path() const { return dir_; }
  std::size_t files() const { return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir_), {})); }

 private:
  fs::path dir_;
  std::optional<std::string> old_;
};

TEST(Db3Recording, FileCompressedBagGivesEveryMessageThroughOneTemporaryCopyAtATime) {
  const nlohmann::json want = expectedJson();
  const TempDirScope tmp("db3_file_tmp");
  {
    const std::unique_ptr<Recording> rec = openDb3Recording(kData / "dive_db3_file");
    EXPECT_EQ(tmp.files(), 0u) << "nothing is decompressed before reading";
    EXPECT_EQ(rec->compression(), "zstd by file (compression_mode FILE): each file is decompressed into " +
                                      tmp.path().string() + " (TMPDIR) while it is read, one at a time");
    // Topics and counts from metadata.yaml; each topic spans the bag's time span.
    std::int64_t first = std::numeric_limits<std::int64_t>::max(), last = 0;
    for (const auto& m : want["messages"]) {
      first = std::min<std::int64_t>(first, std::stoll(m["log_time_ns"].get<std::string>()));
      last = std::max<std::int64_t>(last, std::stoll(m["log_time_ns"].get<std::string>()));
    }
    nlohmann::json topics = want["topics"];
    for (auto& t : topics) {
      t["first_ns"] = std::to_string(first);
      t["last_ns"] = std::to_string(last);
    }
    expectTopics(*rec, topics);
    RecordedMessage m;
    ASSERT_TRUE(rec->next({}, m));
    EXPECT_EQ(tmp.files(), 1u) << "the first file's decompressed copy";
    EXPECT_EQ(Bytes(m.data.begin(), m.data.end()), fromHex(want["messages"][0]["data"]));
  }
  EXPECT_EQ(tmp.files(), 0u) << "the copy is removed with the recording";
  const std::unique_ptr<Recording> rec = openDb3Recording(kData / "dive_db3_file");
  expectMessages(*rec, want["messages"], {});  // the second file streamed, without its content size
  EXPECT_EQ(tmp.files(), 0u) << "each copy is removed once read";
}

// A .db3 in WAL mode (rosbag2's resilient preset) makes sqlite create -wal and -shm files beside the file
// it reads: beside a decompressed copy they would stay in TMPDIR after the copy went. Nothing lies
// beside the fresh copy (no -wal file), so it is read immutable, and nothing is left.
TEST(Db3Recording, FileCompressedBagInWalModeLeavesNothingInTheTemporaryFolder) {
  const TempDirScope tmp("db3_wal_tmp");
  {
    const std::unique_ptr<Recording> rec = openDb3Recording(kData / "dive_db3_file_wal");
    RecordedMessage m;
    ASSERT_TRUE(rec->next({}, m));
    EXPECT_EQ(tmp.files(), 1u) << "the first file's decompressed copy alone";
  }
  EXPECT_EQ(tmp.files(), 0u);
  const std::unique_ptr<Recording> rec = openDb3Recording(kData / "dive_db3_file_wal");
  expectMessages(*rec, expectedJson()["messages"], {});
  EXPECT_EQ(tmp.files(), 0u) << "each copy and whatever sqlite made beside it removed once read";
}

// The bag kData/name copied into a fresh scratch folder (sqlite may write beside what it reads there),
// and the names of the files in it.
fs::path scratchCopyOfBag(const std::string& name) {
  const fs::path dir = cenote::test::freshScratchDirectory("db3_" + name) / name;
  fs::copy(kData / name, dir);
  return dir;
}
std::vector<std::string> fileNames(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// rosbag2's resilient preset records in WAL mode. Read as sqlite reads a WAL file, such a bag would get
// -wal and -shm files made beside it (and would not open in a read-only folder); with every message in
// the .db3 files themselves (no -wal file beside them), it is read immutable and its folder is left
// as it was.
TEST(Db3Recording, PlainBagInWalModeIsReadWithoutMakingFilesBesideIt) {
  const fs::path bag = scratchCopyOfBag("dive_db3_wal");
  const std::vector<std::string> before = fileNames(bag);
  ASSERT_EQ(before, (std::vector<std::string>{"dive_db3_wal_0.db3", "dive_db3_wal_1.db3", "metadata.yaml"}));
  {
    const std::unique_ptr<Recording> rec = openDb3Recording(bag);
    expectTopics(*rec, expectedJson()["topics"]);
    expectMessages(*rec, expectedJson()["messages"], {});
  }
  EXPECT_EQ(fileNames(bag), before);
}

// A WAL-mode recorder killed before its first checkpoint leaves its messages in the -wal files
// (gen_db3.py checks that the .db3 files alone hold none): those are read, every message of both files.
TEST(Db3Recording, WalModeRecorderKilledBeforeACheckpointIsReadFromItsWalFiles) {
  const fs::path bag = scratchCopyOfBag("dive_db3_wal_killed");
  const std::unique_ptr<Recording> rec = openDb3Recording(bag);
  EXPECT_EQ(rec->truncation(), "no metadata.yaml (the recorder did not finish): read the 2 .db3 files in the folder");
  expectTopics(*rec, expectedJson()["topics"]);
  expectMessages(*rec, expectedJson()["messages"], {});
}

TEST(Db3Recording, AnUnfinishedCompressedBagIsReadFromItsFilesAndSaysSo) {
  const TempDirScope tmp("db3_unfinished_tmp");
  // Topics counted from the compressed file's decompressed copy; nothing says how the bag was compressed.
  expectBag("dive_db3_unfinished_file",
            "no metadata.yaml (the recorder did not finish): read the 2 .db3 files in the folder (1 of them .db3.zstd)",
            "");
  EXPECT_EQ(tmp.files(), 0u);
  expectBag("dive_db3_unfinished_message",
            "no metadata.yaml (the recorder did not finish): read the 2 .db3 files in the folder", "");
}

TEST(Db3Recording, DamagedCompressionNamesTheFileTheMessageOrTheCut) {
  const nlohmann::json damaged = nlohmann::json::parse(std::ifstream(kData / "dive_db3_damaged" / "damaged.json"));
  const std::unique_ptr<Recording> rec = openDb3Recording(kData / "dive_db3_damaged");
  RecordedMessage m;
  try {
    while (rec->next({}, m)) {
    }
    FAIL() << "expected an IoError";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()), "ROS 2 bag file " + (kData / "dive_db3_damaged" / damaged["file"]).string() +
                                         ": message (row id " + std::to_string(damaged["row_id"].get<int>()) + ") on " +
                                         damaged["topic"].get<std::string>() +
                                         " (compression_mode MESSAGE): zstd: not a zstd frame");
  }
  // A FILE-compressed file cut short.
  const TempDirScope tmp("db3_cut_tmp");
  const fs::path bag = fs::path(::testing::TempDir()) / "db3_file_cut";
  fs::remove_all(bag);
  fs::copy(kData / "dive_db3_file", bag);
  const fs::path file = bag / "dive_db3_file_0.db3.zstd";
  fs::resize_file(file, fs::file_size(file) / 2);
  const std::unique_ptr<Recording> cut = openDb3Recording(bag);
  try {
    cut->next({}, m);
    FAIL() << "expected an IoError";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()), file.string() + ": zstd: the file ends inside a frame (cut short)");
  }
}

// metadata.yaml may list any name: one too long for the file system is an IoError with the system's reason,
// plain or compressed by file.
TEST(Db3Recording, ListedFileNameTooLongIsAnIoErrorNamingIt) {
  const fs::path bag = fs::path(::testing::TempDir()) / "name_too_long";
  fs::create_directories(bag);
  const std::string stem(300, 'a');  // above NAME_MAX (255)
  for (const std::string& mode : {std::string("\"\""), std::string("FILE")}) {
    const std::string name = stem + (mode == "FILE" ? ".db3.zstd" : ".db3");
    std::ofstream(bag / "metadata.yaml") << "rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n"
                                            "  compression_format: "
                                         << (mode == "FILE" ? "zstd" : "\"\"") << "\n  compression_mode: " << mode
                                         << "\n  starting_time: {nanoseconds_since_epoch: 0}\n  duration: {nanoseconds: 0}"
                                            "\n  topics_with_message_count: []\n  relative_file_paths: ["
                                         << name << "]\n";
    try {
      const std::unique_ptr<Recording> rec = openDb3Recording(bag);
      RecordedMessage m;
      rec->next({}, m);  // a FILE-compressed bag opens its files as reading reaches them
      FAIL() << "expected an IoError (" << mode << ")";
    } catch (const IoError& e) {
      EXPECT_EQ(std::string(e.what()), "cannot read ROS 2 bag file " + (bag / name).string() + ": File name too long")
          << mode;
    }
  }
}

TEST(Db3Recording, MetadataThatIsNotAMappingNamesTheFile) {
  const fs::path bag = fs::path(::testing::TempDir()) / "scalar_metadata";
  fs::create_directories(bag);
  for (const char* yaml : {"rosbag2_bagfile_information\n", "- rosbag2_bagfile_information\n", ""}) {
    std::ofstream(bag / "metadata.yaml") << yaml;
    try {
      openDb3Recording(bag);
      FAIL() << "expected an IoError for '" << yaml << "'";
    } catch (const IoError& e) {
      EXPECT_EQ(std::string(e.what()), (bag / "metadata.yaml").string() + ": no rosbag2_bagfile_information mapping")
          << "for '" << yaml << "'";
    }
  }
}

TEST(Db3Recording, UnknownCompressionIsAClearErrorNamingIt) {
  const fs::path bag = fs::path(::testing::TempDir()) / "compressed_bag";
  fs::create_directories(bag);
  const std::string where = (bag / "metadata.yaml").string() + ": rosbag2_bagfile_information.";
  auto error = [&](const std::string& format, const std::string& mode) {
    std::ofstream(bag / "metadata.yaml") << "rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n"
                                            "  compression_format: "
                                         << format << "\n  compression_mode: " << mode
                                         << "\n  relative_file_paths: [dive_0.db3.lz4]\n";
    try {
      openDb3Recording(bag);
    } catch (const IoError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error("lz4", "FILE"), where +
                                      "compression_format is 'lz4' (compression_mode FILE): this reader decompresses "
                                      "zstd, the compressor rosbag2 ships; decompress the bag first (ros2 bag convert)");
  EXPECT_EQ(error("\"\"", "message"),
            where + "compression_format is '' (compression_mode message): this reader decompresses "
                    "zstd, the compressor rosbag2 ships; decompress the bag first (ros2 bag convert)");
  EXPECT_EQ(error("zstd", "CHUNK"), where + "compression_mode is 'CHUNK': rosbag2 writes NONE, FILE or MESSAGE");
}

}  // namespace
}  // namespace cenote::io::test
