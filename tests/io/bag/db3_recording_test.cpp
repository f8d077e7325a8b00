// ROS 2 sqlite3 bags written by Python's sqlite3 in rosbag2's tables (tests/io/bag/gen/gen_db3.py) with
// the CDR bytes of Foxglove's serialiser: topics, counts, time spans and every message's bytes in
// timestamp order across the bag's two files; a bag whose recorder never wrote metadata.yaml; the
// errors for a file that is not a database and for a missing bag.
#include "io/bag/db3_recording.h"

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "common/error.h"
#include "tests/io/bag/ros2_test_data.h"

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
  const nlohmann::json want = expectedJson();
  const std::unique_ptr<Recording> rec = openDb3Recording(kData / "dive_db3_cut");
  expectTopics(*rec, want["topics"]);
  EXPECT_EQ(rec->truncation(), "no metadata.yaml (the recorder did not finish): read the 2 .db3 files in the folder");
  expectMessages(*rec, want["messages"], {});
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

TEST(Db3Recording, CompressedBagIsAClearError) {
  const fs::path bag = fs::path(::testing::TempDir()) / "compressed_bag";
  fs::create_directories(bag);
  std::ofstream(bag / "metadata.yaml") << "rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n"
                                          "  compression_format: zstd\n  compression_mode: FILE\n"
                                          "  relative_file_paths: [dive_0.db3.zstd]\n";
  try {
    openDb3Recording(bag);
    FAIL() << "expected an IoError";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()), (bag / "metadata.yaml").string() +
                                         ": rosbag2_bagfile_information.compression_mode is 'FILE': compressed bags "
                                         "are not read; convert it first (ros2 bag convert)");
  }
}

}  // namespace
}  // namespace cenote::io::test
