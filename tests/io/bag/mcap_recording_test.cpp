// MCAP recordings written by the MCAP team's own writer (@mcap/core, tests/io/bag/gen/gen_mcap.js):
// topics, counts, time spans and every message's bytes against what the generator wrote
// (expected.json), for chunks uncompressed, zstd and lz4, unchunked files and files without a summary;
// files cut short (inside a compressed chunk, inside an uncompressed one, between records); a CRC
// mismatch, a chunk size field beyond its records and an unknown compression with their exact error text.
#include "io/bag/mcap_recording.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <zlib.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "common/error.h"
#include "tests/io/bag/ros2_test_data.h"

namespace cenote::io::test {
namespace {

namespace fs = std::filesystem;

Bytes readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), {});
}

fs::path writeFile(const std::string& name, const Bytes& bytes, std::size_t size) {
  const fs::path path = fs::path(::testing::TempDir()) / name;
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(size));
  return path;
}

struct Message {
  std::string topic;
  std::int64_t log_time_ns;
  Bytes data;
};

std::vector<Message> expectedMessages() {
  std::vector<Message> out;
  for (const auto& m : expectedJson()["messages"])
    out.push_back({m["topic"], std::stoll(m["log_time_ns"].get<std::string>()), fromHex(m["data"])});
  return out;
}

std::vector<Message> readAll(Recording& rec, const std::vector<std::string>& wanted = {}) {
  std::vector<Message> out;
  RecordedMessage m;
  while (rec.next(wanted, m)) out.push_back({m.topic->name, m.log_time_ns, Bytes(m.data.begin(), m.data.end())});
  return out;
}

void expectMessages(const std::vector<Message>& got, const std::vector<Message>& want, std::size_t count) {
  ASSERT_EQ(got.size(), count);
  for (std::size_t i = 0; i < count; ++i) {
    EXPECT_EQ(got[i].topic, want[i].topic) << "message " << i;
    EXPECT_EQ(got[i].log_time_ns, want[i].log_time_ns) << "message " << i;
    EXPECT_EQ(got[i].data, want[i].data) << "message " << i << " on " << want[i].topic;
  }
}

struct Chunk {
  std::uint64_t start, length;
};
std::vector<Chunk> chunks(const std::string& file) {
  std::vector<Chunk> out;
  for (const auto& c : expectedJson()["files"][file]["chunks"])
    out.push_back({std::stoull(c["start"].get<std::string>()), std::stoull(c["length"].get<std::string>())});
  return out;
}
// How many messages lie in chunks before chunk k.
std::size_t messagesBeforeChunk(const std::string& file, std::size_t k) {
  const auto& of = expectedJson()["files"][file]["chunk_of_message"];
  return static_cast<std::size_t>(
      std::count_if(of.begin(), of.end(), [&](const auto& c) { return c.template get<std::size_t>() < k; }));
}

class McapFile : public ::testing::TestWithParam<std::string> {};

TEST_P(McapFile, TopicsCountsAndTimeSpansAreTheWritersOnes) {
  const std::unique_ptr<Recording> rec = openMcapRecording(kData / (GetParam() + ".mcap"));
  expectTopics(*rec, expectedJson()["topics"]);
  EXPECT_EQ(rec->truncation(), "");
}

TEST_P(McapFile, EveryMessageInFileOrderWithItsBytes) {
  const std::unique_ptr<Recording> rec = openMcapRecording(kData / (GetParam() + ".mcap"));
  const std::vector<Message> want = expectedMessages();
  ASSERT_EQ(want.size(), 34u);
  expectMessages(readAll(*rec), want, want.size());
  RecordedMessage m;
  EXPECT_FALSE(rec->next({}, m)) << "the end stays the end";
}

TEST_P(McapFile, OnlyTheWantedTopics) {
  const std::unique_ptr<Recording> rec = openMcapRecording(kData / (GetParam() + ".mcap"));
  std::vector<Message> want = expectedMessages();
  std::erase_if(want, [](const Message& m) { return m.topic != "/odom" && m.topic != "/tf"; });
  ASSERT_EQ(want.size(), 14u);
  expectMessages(readAll(*rec, {"/tf", "/odom"}), want, want.size());
}

INSTANTIATE_TEST_SUITE_P(ChunksAndLayouts, McapFile,
                         ::testing::Values("dive_none", "dive_zstd", "dive_lz4", "dive_unchunked", "dive_nosummary"));

TEST(McapRecording, TypeNamesInRos1Spelling) {
  EXPECT_EQ(ros1TypeName("sensor_msgs/msg/Image"), "sensor_msgs/Image");
  EXPECT_EQ(ros1TypeName("tf2_msgs/msg/TFMessage"), "tf2_msgs/TFMessage");
  EXPECT_EQ(ros1TypeName("sensor_msgs/Image"), "sensor_msgs/Image");
}

TEST(McapRecording, CutInsideAZstdChunkGivesEveryMessageOfTheChunksBefore) {
  const Bytes file = readFile(kData / "dive_zstd.mcap");
  const std::vector<Chunk> c = chunks("dive_zstd");
  ASSERT_EQ(c.size(), 17u);
  const std::size_t cut = c[9].start + c[9].length / 2;
  const fs::path path = writeFile("cut_zstd.mcap", file, cut);
  const std::unique_ptr<Recording> rec = openMcapRecording(path);
  const std::size_t complete = messagesBeforeChunk("dive_zstd", 9);
  ASSERT_EQ(complete, 15u);
  EXPECT_EQ(rec->truncation(), "cut at byte " + std::to_string(cut) + " inside the chunk record at byte " +
                                   std::to_string(c[9].start) + " (" + std::to_string(cut - c[9].start - 9) + " of its " +
                                   std::to_string(c[9].length - 9) + " bytes): no footer; 15 complete messages read");
  std::uint64_t counted = 0;
  for (const TopicInfo& t : rec->topics()) counted += t.message_count;
  EXPECT_EQ(counted, complete) << "counts from the scan";
  expectMessages(readAll(*rec), expectedMessages(), complete);
}

TEST(McapRecording, CutInsideAnUncompressedChunkGivesItsCompleteMessagesToo) {
  const Bytes file = readFile(kData / "dive_none.mcap");
  const std::vector<Chunk> c = chunks("dive_none");
  // The first chunk that holds three messages or more, cut 3 bytes after the end of its second message
  // (found by its bytes: a message record ends with its data).
  std::size_t k = 0;
  while (messagesBeforeChunk("dive_none", k + 1) - messagesBeforeChunk("dive_none", k) < 3) ++k;
  ASSERT_EQ(k, 5u);
  const std::size_t complete = messagesBeforeChunk("dive_none", k) + 2;
  const std::vector<Message> want = expectedMessages();
  const Bytes& second = want[complete - 1].data;
  const auto at = std::search(file.begin() + static_cast<std::ptrdiff_t>(c[k].start), file.end(), second.begin(),
                              second.end());
  const std::size_t cut = static_cast<std::size_t>(at - file.begin()) + second.size() + 3;
  ASSERT_LT(cut, c[k].start + c[k].length);
  const std::unique_ptr<Recording> rec = openMcapRecording(writeFile("cut_none.mcap", file, cut));
  EXPECT_EQ(rec->truncation(), "cut at byte " + std::to_string(cut) + " inside the chunk record at byte " +
                                   std::to_string(c[k].start) + " (" + std::to_string(cut - c[k].start - 9) + " of its " +
                                   std::to_string(c[k].length - 9) + " bytes): no footer; " + std::to_string(complete) +
                                   " complete messages read");
  expectMessages(readAll(*rec), want, complete);
}

TEST(McapRecording, CutBetweenRecordsSaysNoFooter) {
  const Bytes file = readFile(kData / "dive_lz4.mcap");
  const std::vector<Chunk> c = chunks("dive_lz4");
  const std::size_t cut = c[4].start + c[4].length;  // the chunk whole, its message indexes gone
  const std::unique_ptr<Recording> rec = openMcapRecording(writeFile("cut_lz4.mcap", file, cut));
  const std::size_t complete = messagesBeforeChunk("dive_lz4", 5);
  EXPECT_EQ(rec->truncation(),
            "cut at byte " + std::to_string(cut) + ": no footer; " + std::to_string(complete) + " complete messages read");
  expectMessages(readAll(*rec), expectedMessages(), complete);
}

// A damaged chunk is stepped over, named with its offset and the messages its Message Index records
// list; reading goes on with the next chunk.
TEST(McapRecording, CrcMismatchSkipsTheChunkAndNamesIt) {
  Bytes file = readFile(kData / "dive_none.mcap");
  const std::vector<Chunk> c = chunks("dive_none");
  // Flip one bit of the first message that lies in chunk 3.
  const std::size_t first = messagesBeforeChunk("dive_none", 3);
  const Bytes data = expectedMessages()[first].data;
  const auto at = std::search(file.begin() + static_cast<std::ptrdiff_t>(c[3].start), file.end(), data.begin(), data.end());
  ASSERT_LT(static_cast<std::size_t>(at - file.begin()), c[3].start + c[3].length);
  at[data.size() - 1] ^= 0x01;
  // The chunk's records: after opcode, length, start/end time, uncompressed size, CRC, "" and records length.
  const std::size_t records = c[3].start + 9 + 8 + 8 + 8 + 4 + 4 + 8;
  const std::size_t size = c[3].start + c[3].length - records;
  const std::uint32_t stored = file[c[3].start + 33] | file[c[3].start + 34] << 8 | file[c[3].start + 35] << 16 |
                               static_cast<std::uint32_t>(file[c[3].start + 36]) << 24;
  const auto computed = static_cast<std::uint32_t>(crc32(0, file.data() + records, static_cast<uInt>(size)));
  ASSERT_NE(stored, computed);
  const fs::path path = writeFile("bad_crc.mcap", file, file.size());
  const std::unique_ptr<Recording> rec = openMcapRecording(path);
  RecordedMessage m;
  for (std::size_t i = 0; i < first; ++i) ASSERT_TRUE(rec->next({}, m)) << "chunks 0..2 are whole";
  char hex[2][16];
  std::snprintf(hex[0], sizeof hex[0], "0x%08x", stored);
  std::snprintf(hex[1], sizeof hex[1], "0x%08x", computed);
  const std::size_t after = messagesBeforeChunk("dive_none", 4);
  std::vector<Message> want = expectedMessages();
  std::map<std::string, int> held;
  for (std::size_t i = first; i < after; ++i) ++held[want[i].topic];
  want.erase(want.begin(), want.begin() + static_cast<std::ptrdiff_t>(after));
  expectMessages(readAll(*rec), want, want.size());
  const std::vector<std::string> skipped = rec->skipped();
  ASSERT_EQ(skipped.size(), 1u);
  const std::string damage = path.string() + ": chunk at byte " + std::to_string(c[3].start) +
                             ": CRC mismatch: the chunk stores " + hex[0] + ", its " + std::to_string(size) +
                             " uncompressed bytes give " + hex[1] + "; skipped the chunk (of its " +
                             std::to_string(after - first) + " messages: ";
  EXPECT_EQ(skipped[0].substr(0, damage.size()), damage);
  for (const auto& [topic, n] : held)
    EXPECT_NE(skipped[0].find(std::to_string(n) + " on " + topic), std::string::npos) << skipped[0];
}

// A chunk's uncompressed size field set to 1 GiB (the most a chunk may hold) on a chunk of a few hundred
// bytes: the chunk is damaged like any other, found by decoding its records, and its buffer never takes
// the size the field claims.
TEST(McapRecording, ChunkSizeFieldBeyondItsRecordsSkipsTheChunkWithoutAllocatingIt) {
  const std::uint64_t claimed = std::uint64_t{1} << 30;
  const std::map<std::string, std::string> damage = {{"dive_none", "uncompressed chunk of N bytes declares "},
                                                     {"dive_zstd", "zstd gave N bytes, the chunk declares "},
                                                     {"dive_lz4", "lz4 frame gave N bytes, the chunk declares "}};
  for (const auto& [name, what] : damage) {
    Bytes file = readFile(kData / (name + ".mcap"));
    const std::vector<Chunk> c = chunks(name);
    const std::size_t at = c[3].start + 9 + 8 + 8;  // after opcode, length, message start and end time
    std::uint64_t size = 0;
    for (int i = 0; i < 8; ++i) {
      size |= std::uint64_t{file[at + i]} << (8 * i);
      file[at + i] = static_cast<std::uint8_t>(claimed >> (8 * i));
    }
    const fs::path path = writeFile("huge_" + name + ".mcap", file, file.size());
    rusage before{};
    getrusage(RUSAGE_SELF, &before);
    const std::unique_ptr<Recording> rec = openMcapRecording(path);
    const std::vector<Message> got = readAll(*rec);
    rusage after{};
    getrusage(RUSAGE_SELF, &after);
    EXPECT_EQ(got.size(), expectedMessages().size() - (messagesBeforeChunk(name, 4) - messagesBeforeChunk(name, 3)))
        << name << ": every message but chunk 3's";
    ASSERT_EQ(rec->skipped().size(), 1u) << name;
    std::string want = what;
    want.replace(want.find('N'), 1, std::to_string(size));
    want = path.string() + ": chunk at byte " + std::to_string(c[3].start) + ": " + want + std::to_string(claimed) +
           "; skipped the chunk (of its ";
    EXPECT_EQ(rec->skipped()[0].substr(0, want.size()), want) << name;
    EXPECT_LT(after.ru_maxrss - before.ru_maxrss, 256 * 1024) << name << ": peak resident KiB grew";
  }
}

TEST(McapRecording, UnknownCompressionNamesTheFileAndTheChunk) {
  const fs::path path = kData / "dive_bz2.mcap";
  const std::unique_ptr<Recording> rec = openMcapRecording(path);
  EXPECT_EQ(rec->topics().size(), 8u) << "the summary is readable";
  RecordedMessage m;
  try {
    rec->next({}, m);
    FAIL() << "expected an IoError";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()), path.string() + ": chunk at byte " + std::to_string(chunks("dive_bz2")[0].start) +
                                         ": unknown compression 'bz2' (this reader reads none, zstd and lz4)");
  }
}

TEST(McapRecording, NotAnMcapFileAndMissingFile) {
  const fs::path text = writeFile("not.mcap", Bytes{'h', 'e', 'l', 'l', 'o', ' ', 'm', 'c', 'a', 'p'}, 10);
  try {
    openMcapRecording(text);
    FAIL() << "expected an IoError";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()),
              text.string() + ": not an MCAP file (its first 8 bytes are not the MCAP magic 89 4d 43 41 50 30 0d 0a)");
  }
  EXPECT_THROW(openMcapRecording(fs::path(::testing::TempDir()) / "absent.mcap"), NotFoundError);
}

}  // namespace
}  // namespace cenote::io::test
