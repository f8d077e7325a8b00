// ROS 1 bags written by ROS's own rosbag (python3-rosbag, tests/io/bag/write_test_bags.py): every
// message type cenote reads, uncompressed / bz2 / lz4 chunks, bags cut mid-chunk, damage.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <zlib.h>

#include "common/error.h"
#include "io/bag/recording.h"
#include "io/bag/ros1_bag.h"
#include "io/bag/ros_image.h"
#include "io/bag/ros_messages.h"
#include "tests/support/scratch_dir.h"

namespace cenote::io {
namespace {

namespace fs = std::filesystem;

// The bags, written once per test process (its own folder: ctest may run tests side by side).
struct BagFolder {
  fs::path dir = test::freshScratchDirectory("ros1_bags_" + std::to_string(getpid()));
  BagFolder() {
    const std::string cmd = "/usr/bin/python3 " CENOTE_SOURCE_DIR "/tests/io/bag/write_test_bags.py " + dir.string();
    if (std::system(cmd.c_str()) != 0) ADD_FAILURE() << "failed: " << cmd;
  }
  ~BagFolder() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
};
const fs::path& bagDir() {
  static const BagFolder folder;
  return folder.dir;
}

nlohmann::json expected() {
  std::ifstream in(bagDir() / "expected.json");
  return nlohmann::json::parse(in);
}

// Every message of `topic`, its bytes copied.
struct Copied {
  std::string topic, type;
  std::int64_t log_time_ns;
  std::vector<std::uint8_t> data;
};
std::vector<Copied> readAll(Recording& bag, const std::vector<std::string>& wanted = {}) {
  std::vector<Copied> out;
  RecordedMessage m;
  while (bag.next(wanted, m)) {
    out.push_back({m.topic->name, m.topic->type, m.log_time_ns, std::vector<std::uint8_t>(m.data.begin(), m.data.end())});
  }
  return out;
}

// The one message of `topic` in messages.bag.
class OneMessage {
 public:
  explicit OneMessage(const std::string& topic) : bag_(openRecording(bagDir() / "messages.bag")) {
    if (!bag_->next({topic}, message_)) ADD_FAILURE() << "no message on " << topic;
  }
  const RecordedMessage& operator*() const { return message_; }

 private:
  std::unique_ptr<Recording> bag_;
  RecordedMessage message_;
};

const TopicInfo* findTopic(const Recording& bag, const std::string& name) {
  for (const TopicInfo& t : bag.topics()) {
    if (t.name == name) return &t;
  }
  return nullptr;
}

TEST(Ros1Bag, TopicsTypesAndCountsComeFromTheIndex) {
  const auto bag = openRecording(bagDir() / "messages.bag");
  EXPECT_EQ(bag->topics().size(), 11u);
  const TopicInfo* info = findTopic(*bag, "/cam/info");
  ASSERT_NE(info, nullptr);
  EXPECT_EQ(info->type, "sensor_msgs/CameraInfo");
  EXPECT_EQ(info->message_count, 1u);
  EXPECT_EQ(info->first_ns, 1700000000123456789);
  EXPECT_EQ(bag->truncation(), "");
  for (const char* c : {"none", "bz2", "lz4"}) {
    Ros1Bag seq(bagDir() / (std::string("seq_") + c + ".bag"));
    ASSERT_EQ(seq.topics().size(), 2u) << c;
    const TopicInfo* image = findTopic(seq, "/cam/image");
    ASSERT_NE(image, nullptr);
    EXPECT_EQ(image->message_count, 240u) << c;
    EXPECT_EQ(image->first_ns, 100'000'000'000) << c;
    EXPECT_EQ(image->last_ns, 123'900'000'000) << c;
    EXPECT_EQ(seq.chunkCompressions().size(), 1u);
    EXPECT_GT(seq.chunkCompressions().at(c), 10u) << c;
  }
}

TEST(Ros1Bag, UncompressedBz2AndLz4ChunksGiveTheSameMessagesInFileOrder) {
  Ros1Bag none(bagDir() / "seq_none.bag");
  const std::vector<Copied> reference = readAll(none);
  ASSERT_EQ(reference.size(), 480u);
  for (std::size_t i = 0; i < reference.size(); ++i) {
    ASSERT_EQ(reference[i].topic, i % 2 == 0 ? "/cam/image" : "/odom") << "message " << i;
  }
  for (const char* c : {"bz2", "lz4"}) {
    Ros1Bag bag(bagDir() / (std::string("seq_") + c + ".bag"));
    const std::vector<Copied> got = readAll(bag);
    ASSERT_EQ(got.size(), reference.size()) << c;
    for (std::size_t i = 0; i < got.size(); ++i) {
      ASSERT_EQ(got[i].topic, reference[i].topic) << c << " message " << i;
      ASSERT_EQ(got[i].log_time_ns, reference[i].log_time_ns) << c << " message " << i;
      ASSERT_EQ(got[i].data, reference[i].data) << c << " message " << i;
    }
  }
  // Only the topics asked for, the pixels as written (value = index).
  Ros1Bag lz4(bagDir() / "seq_lz4.bag");
  RecordedMessage m;
  for (int i = 0; i < 240; ++i) {
    ASSERT_TRUE(lz4.next({"/cam/image"}, m)) << i;
    const cv::Mat pixels = imageToMat(decodeImage(m), m.topic->name);
    ASSERT_EQ(pixels.at<std::uint8_t>(7, 15), i) << "image " << i;
  }
  EXPECT_FALSE(lz4.next({"/cam/image"}, m));
}

TEST(Ros1Bag, ABagCutMidChunkReadsEveryCompleteMessageBeforeTheCut) {
  const nlohmann::json e = expected();
  for (const char* name :
       {"cut_none.bag", "cut_bz2.bag", "cut_lz4.bag", "crashed_none.bag", "crashed_bz2.bag", "crashed_lz4.bag"}) {
    const nlohmann::json& x = e.at(name);
    const auto bag = openRecording(bagDir() / name);
    const std::uint64_t complete = x.at("complete");
    const std::vector<Copied> got = readAll(*bag);
    EXPECT_EQ(got.size(), complete) << name;
    EXPECT_EQ(bag->truncation(), "cut at byte " + std::to_string(x.at("size").get<std::uint64_t>()) +
                                     ", inside the chunk at byte " +
                                     std::to_string(x.at("chunk_pos").get<std::uint64_t>()) + ": no index; " +
                                     std::to_string(complete) + " complete messages read")
        << name;
    // The same messages as the whole bag's first ones, and the scan's counts.
    Ros1Bag whole(bagDir() / "seq_none.bag");
    const std::vector<Copied> reference = readAll(whole);
    for (std::size_t i = 0; i < got.size(); ++i) ASSERT_EQ(got[i].data, reference[i].data) << name << " message " << i;
    std::uint64_t counted = 0;
    for (const TopicInfo& t : bag->topics()) {
      counted += t.message_count;
      // The scan (index records of closed chunks, the cut chunk read) agrees with the messages read.
      std::uint64_t n = 0;
      std::int64_t first = 0, last = 0;
      for (const Copied& c : got) {
        if (c.topic != t.name) continue;
        first = n == 0 ? c.log_time_ns : std::min(first, c.log_time_ns);
        last = n == 0 ? c.log_time_ns : std::max(last, c.log_time_ns);
        ++n;
      }
      EXPECT_EQ(t.message_count, n) << name << " " << t.name;
      EXPECT_EQ(t.first_ns, first) << name << " " << t.name;
      EXPECT_EQ(t.last_ns, last) << name << " " << t.name;
    }
    EXPECT_EQ(counted, complete) << name;
  }
}

TEST(Ros1Bag, UnknownCompressionIsAnIoErrorNamingTheFileAndOffset) {
  const std::string path = (bagDir() / "zstd.bag").string();
  const std::uint64_t pos = expected().at("zstd.bag").at("first_chunk_pos");
  try {
    Ros1Bag bag(path);  // the index names each chunk's compression: the error comes at once
    FAIL() << "no error";
  } catch (const IoError& err) {
    EXPECT_EQ(std::string(err.what()), "bag " + path + ", byte " + std::to_string(pos) +
                                           " (chunk): unknown compression 'zstd' (a ROS 1 bag's chunks are none, bz2 "
                                           "or lz4)");
  }
}

// A damaged chunk is stepped over, named with its offset and the messages it held (rosbag's own
// index says which); every message of the other chunks is read, in order.
TEST(Ros1Bag, CorruptBz2ChunkIsSkippedNamingItsOffsetAndTopics) {
  const fs::path path = test::freshScratchDirectory("corrupt_bz2") / "corrupt.bag";
  fs::copy_file(bagDir() / "seq_bz2.bag", path);
  const nlohmann::json x = expected().at("seq_bz2.bag");
  const std::uint64_t chunk = x.at("middle_chunk_pos");
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(x.at("middle_chunk_data_pos").get<std::uint64_t>() + 40));
    const char junk[16] = {'j', 'u', 'n', 'k', 'j', 'u', 'n', 'k', 'j', 'u', 'n', 'k', 'j', 'u', 'n', 'k'};
    f.write(junk, sizeof(junk));
  }
  Ros1Bag bag(path);
  Ros1Bag whole(bagDir() / "seq_bz2.bag");
  const std::vector<Copied> got = readAll(bag), all = readAll(whole);
  const std::uint64_t held_image = x.at("middle_chunk_held").at("/cam/image");
  const std::uint64_t held_odom = x.at("middle_chunk_held").at("/odom");
  ASSERT_EQ(all.size(), x.at("messages").get<std::size_t>());
  ASSERT_EQ(got.size(), all.size() - held_image - held_odom);
  ASSERT_EQ(bag.skipped().size(), 1u);
  EXPECT_THAT(bag.skipped()[0], testing::StartsWith("bag " + path.string() + ", byte " + std::to_string(chunk) +
                                                    " (chunk): bz2 data are corrupt"));
  EXPECT_THAT(bag.skipped()[0], testing::EndsWith("; skipped the chunk (of its " + std::to_string(held_image + held_odom) +
                                                  " messages: " + std::to_string(held_image) + " on /cam/image, " +
                                                  std::to_string(held_odom) + " on /odom)"));
  // What was read is every message of the whole bag outside that chunk, in the same order.
  std::size_t k = 0;
  for (const Copied& m : all) {
    if (k < got.size() && got[k].log_time_ns == m.log_time_ns && got[k].topic == m.topic && got[k].data == m.data) ++k;
  }
  EXPECT_EQ(k, got.size());
  EXPECT_EQ(bag.truncation(), "");
}

// A chunk whose size field says 1 GiB but whose data decode to a few KiB is damage like any other, found
// by decoding the data; its buffer grows with what decodes, never to the size the field claims.
TEST(Ros1Bag, ChunkSizeFieldBeyondItsDataIsSkippedWithoutAllocatingIt) {
  const std::uint32_t claimed = (std::uint32_t{1} << 30) - 1;  // just within the 1 GiB a chunk may hold
  for (const char* c : {"bz2", "lz4"}) {
    const std::string name = std::string("seq_") + c + ".bag";
    const nlohmann::json x = expected().at(name);
    const std::uint64_t chunk = x.at("middle_chunk_pos");
    const fs::path path = test::freshScratchDirectory(std::string("huge_size_") + c) / "huge.bag";
    fs::copy_file(bagDir() / name, path);
    std::uint32_t size = 0;
    {
      std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
      std::string head(256, '\0');
      f.seekg(static_cast<std::streamoff>(chunk));
      f.read(head.data(), static_cast<std::streamsize>(head.size()));
      const std::size_t at = head.find("size=") + 5;  // the chunk header's uncompressed size
      std::memcpy(&size, head.data() + at, sizeof size);
      f.seekp(static_cast<std::streamoff>(chunk + at));
      f.write(reinterpret_cast<const char*>(&claimed), sizeof claimed);
    }
    rusage before{};
    getrusage(RUSAGE_SELF, &before);
    Ros1Bag bag(path);
    readAll(bag);
    rusage after{};
    getrusage(RUSAGE_SELF, &after);
    ASSERT_EQ(bag.skipped().size(), 1u) << c;
    EXPECT_THAT(bag.skipped()[0],
                testing::StartsWith("bag " + path.string() + ", byte " + std::to_string(chunk) + " (chunk): " + c +
                                    " data are corrupt (" + std::to_string(size) + " of " + std::to_string(claimed) +
                                    " bytes decoded); skipped the chunk (of its "))
        << c;
    EXPECT_LT(after.ru_maxrss - before.ru_maxrss, 256 * 1024) << c << ": peak resident KiB grew";
  }
}

// The index records after a chunk, read when the bag is opened for each topic's first and last time: a
// data length past the end of the file is an error naming the record, not a buffer of that length.
TEST(Ros1Bag, IndexRecordLongerThanTheFileIsAnIoErrorNamingIt) {
  const nlohmann::json x = expected().at("seq_none.bag");
  const fs::path path = test::freshScratchDirectory("long_index_record") / "long.bag";
  fs::copy_file(bagDir() / "seq_none.bag", path);
  std::uint64_t index_record = 0;
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    auto u32At = [&](std::uint64_t at) {
      std::uint32_t v = 0;
      f.seekg(static_cast<std::streamoff>(at));
      f.read(reinterpret_cast<char*>(&v), sizeof v);
      return v;
    };
    // The record after the middle chunk's data (u32 length before them): its header, then its data length.
    const std::uint64_t data_pos = x.at("middle_chunk_data_pos");
    index_record = data_pos + u32At(data_pos - 4);
    const std::uint64_t data_len_at = index_record + 4 + u32At(index_record);
    const std::uint32_t huge = 0xffffffff;
    f.seekp(static_cast<std::streamoff>(data_len_at));
    f.write(reinterpret_cast<const char*>(&huge), sizeof huge);
  }
  EXPECT_THAT([&] { Ros1Bag bag(path); },
              testing::ThrowsMessage<IoError>("bag " + path.string() + ", byte " + std::to_string(index_record) +
                                              ": record data of 4294967295 bytes runs past the file"));
}

// A connection that a chunk defines but the index does not list would be a new topic while reading, and
// a run holds pointers to the topics (its left topic, each image's topic): the topics stay those of the
// open, the new connection is not one, and every message of the others is read.
TEST(Ros1Bag, ConnectionTheIndexDoesNotListAddsNoTopicWhileReading) {
  Ros1Bag bag(bagDir() / "unindexed_connection.bag");
  const std::vector<TopicInfo>& topics = bag.topics();
  ASSERT_EQ(topics.size(), 2u);
  const TopicInfo* const first = topics.data();
  Ros1Bag whole(bagDir() / "seq_none.bag");
  const std::vector<Copied> got = readAll(bag), all = readAll(whole);
  EXPECT_EQ(bag.topics().data(), first);
  ASSERT_EQ(bag.topics().size(), 2u);
  EXPECT_EQ(bag.topics()[0].name, "/cam/image");
  EXPECT_EQ(bag.topics()[1].name, "/odom");
  ASSERT_EQ(got.size(), all.size());
  for (std::size_t i = 0; i < got.size(); ++i) ASSERT_EQ(got[i].data, all[i].data) << "message " << i;
  EXPECT_TRUE(bag.skipped().empty());
}

TEST(Ros1Bag, NotABagAndMissingFileAreNamed) {
  const fs::path dir = test::freshScratchDirectory("not_a_bag");
  std::ofstream(dir / "x.bag") << "hello world, not a bag at all";
  EXPECT_THAT(
      [&] { openRecording(dir / "x.bag"); },
      testing::ThrowsMessage<IoError>(testing::HasSubstr("recording " + (dir / "x.bag").string() + ": not a ROS 1 bag")));
  EXPECT_THAT(
      [&] { openRecording(dir / "absent.bag"); },
      testing::ThrowsMessage<NotFoundError>("cannot read recording " + (dir / "absent.bag").string() + ": no such file"));
}

TEST(RosMessages, ImagesOfEachEncodingBecomeGreyOrBgr) {
  const cv::Mat mono = imageToMat(decodeImage(*OneMessage("/cam/mono")), "/cam/mono");
  ASSERT_EQ(mono.type(), CV_8UC1);
  ASSERT_EQ(mono.size(), cv::Size(3, 2));
  for (int i = 0; i < 6; ++i) EXPECT_EQ(mono.at<std::uint8_t>(i / 3, i % 3), i);
  for (const char* topic : {"/cam/bgr", "/cam/rgb"}) {
    const OneMessage message(topic);
    const RosImage image = decodeImage(*message);
    EXPECT_EQ(image.frame_id, "cam0");
    EXPECT_EQ(image.stamp_ns, 1700000000123456789);
    const cv::Mat bgr = imageToMat(image, topic);
    ASSERT_EQ(bgr.type(), CV_8UC3) << topic;
    for (int i = 0; i < 6; ++i) {
      EXPECT_EQ(bgr.at<cv::Vec3b>(i / 3, i % 3), cv::Vec3b(i, 10 + i, 20 + i)) << topic << " pixel " << i;
    }
  }
}

TEST(RosMessages, AnEncodingNotReadIsAClearErrorNamingTheTopic) {
  EXPECT_THAT([] { imageToMat(decodeImage(*OneMessage("/cam/float")), "/cam/float"); },
              testing::ThrowsMessage<Error>(
                  "topic /cam/float: image encoding 32FC1 is not read; cenote reads mono8/16, bgr8/16, rgb8/16, "
                  "bgra8/16, rgba8/16, bayer_{rggb,bggr,gbrg,grbg}8/16, yuv422 (uyvy) and yuv422_yuy2 (yuyv)"));
}

// encodings.bag's scene (write_test_bags.py): 16x12, the left 8 columns one colour, the right 8
// another, each image made by numpy from that definition, not by OpenCV.
const cv::Vec3b kSceneLeft(20, 60, 200), kSceneRight(210, 120, 30);

cv::Mat encodedScene(const std::string& topic) {
  const auto bag = openRecording(bagDir() / "encodings.bag");
  RecordedMessage m;
  if (!bag->next({topic}, m)) ADD_FAILURE() << "no message on " << topic;
  return imageToMat(decodeImage(m), topic);
}

// The largest difference of any channel from the scene's colour over the pixels at least two away
// from the colour edge and the image border (bilinear demosaicing mixes colours across an edge).
double sceneInteriorError(const cv::Mat& bgr) {
  double worst = 0.0;
  for (int y = 2; y < 10; ++y) {
    for (int x = 2; x < 14; ++x) {
      if (x == 6 || x == 7 || x == 8 || x == 9) continue;
      const cv::Vec3b want = x < 8 ? kSceneLeft : kSceneRight;
      for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(double(bgr.at<cv::Vec3b>(y, x)[c]) - want[c]));
    }
  }
  return worst;
}

TEST(RosMessages, BayerMosaicsOfEveryPatternAreDemosaicedToTheirColours) {
  for (const char* topic : {"/enc/bayer_rggb8", "/enc/bayer_bggr8", "/enc/bayer_gbrg8", "/enc/bayer_grbg8"}) {
    const cv::Mat bgr = encodedScene(topic);
    ASSERT_EQ(bgr.type(), CV_8UC3) << topic;
    ASSERT_EQ(bgr.size(), cv::Size(16, 12)) << topic;
    EXPECT_EQ(sceneInteriorError(bgr), 0.0) << topic;  // a flat colour demosaics to itself
  }
  // 16 bits, little and big endian: the 8-bit mosaic's demosaicing.
  EXPECT_EQ(cv::norm(encodedScene("/enc/bayer_rggb16"), encodedScene("/enc/bayer_rggb8"), cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(encodedScene("/enc/bayer_gbrg16_be"), encodedScene("/enc/bayer_gbrg8"), cv::NORM_INF), 0.0);
}

TEST(RosMessages, SixteenBitImagesBecomeEightBitsInEitherByteOrder) {
  // Samples 257 v + 100: v, whatever the byte order.
  for (const char* topic : {"/enc/mono16", "/enc/mono16_be"}) {
    const cv::Mat grey = encodedScene(topic);
    ASSERT_EQ(grey.type(), CV_8UC1) << topic;
    for (int i = 0; i < 192; ++i) ASSERT_EQ(grey.at<std::uint8_t>(i / 16, i % 16), i) << topic << " pixel " << i;
  }
  for (const char* topic : {"/enc/bgr16", "/enc/rgb16_be", "/enc/rgba16"}) {
    const cv::Mat bgr = encodedScene(topic);
    ASSERT_EQ(bgr.type(), CV_8UC3) << topic;
    for (int x = 0; x < 16; ++x)
      EXPECT_EQ(bgr.at<cv::Vec3b>(5, x), x < 8 ? kSceneLeft : kSceneRight) << topic << " x " << x;
  }
}

TEST(RosMessages, TwelveBitSamplesInSixteenBitImagesUseTheirOwnFullScale) {
  const auto bag = openRecording(bagDir() / "encodings.bag");
  RecordedMessage m;
  ASSERT_TRUE(bag->next({"/enc/mono16_12bit"}, m));
  const RosImage image = decodeImage(m);
  const cv::Mat as_16 = imageToMat(image, "/enc/mono16_12bit"), as_12 = imageToMat(image, "/enc/mono16_12bit", 12);
  for (int i = 0; i < 192; ++i) {  // samples 16 i of 0..4095
    ASSERT_EQ(as_12.at<std::uint8_t>(i / 16, i % 16), std::lround(16 * i * 255.0 / 4095.0)) << "pixel " << i;
    ASSERT_EQ(as_16.at<std::uint8_t>(i / 16, i % 16), std::lround(16 * i * 255.0 / 65535.0)) << "pixel " << i;
  }
}

TEST(RosMessages, Yuv422InBothByteOrdersBecomesBgr) {
  for (const char* topic : {"/enc/yuv422", "/enc/yuv422_yuy2"}) {
    const cv::Mat bgr = encodedScene(topic);
    ASSERT_EQ(bgr.type(), CV_8UC3) << topic;
    double worst = 0.0;  // over every pixel: each pixel pair is one colour
    for (int y = 0; y < 12; ++y) {
      for (int x = 0; x < 16; ++x) {
        const cv::Vec3b want = x < 8 ? kSceneLeft : kSceneRight;
        for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(double(bgr.at<cv::Vec3b>(y, x)[c]) - want[c]));
      }
    }
    EXPECT_LE(worst, 2.0) << topic;  // Y, U and V rounded to integers
  }
  EXPECT_THAT([] { encodedScene("/enc/yuv422_odd"); },
              testing::ThrowsMessage<Error>(
                  "topic /enc/yuv422_odd: image encoding yuv422 needs an even width (two pixels share U and V), got 15"));
}

TEST(RosMessages, CompressedImagesAreDecodedByTheirBytesNotTheFormatString) {
  cv::Mat grey(6, 8, CV_8UC1);
  for (int i = 0; i < 48; ++i) grey.at<std::uint8_t>(i / 8, i % 8) = static_cast<std::uint8_t>(i * 5);
  const OneMessage png_message("/cam/png"), jpeg_message("/cam/jpeg");  // the bytes the images view
  const RosCompressedImage png = decodeCompressedImage(*png_message);
  EXPECT_EQ(png.format, "png");
  EXPECT_EQ(cv::norm(compressedImageToMat(png, "/cam/png"), grey, cv::NORM_INF), 0.0);
  const RosCompressedImage jpeg = decodeCompressedImage(*jpeg_message);
  EXPECT_EQ(jpeg.format, "mono8; jpeg compressed bgr8");
  const cv::Mat decoded = compressedImageToMat(jpeg, "/cam/jpeg");
  ASSERT_EQ(decoded.type(), CV_8UC1);
  EXPECT_LE(cv::norm(decoded, grey, cv::NORM_INF), 3.0);  // JPEG at quality 100
  RosCompressedImage junk = png;
  const std::uint8_t bytes[] = {'G', 'I', 'F', '8', '9', 'a', 0, 0};
  junk.data = bytes;
  EXPECT_THAT(
      [&] { compressedImageToMat(junk, "/cam/png"); },
      testing::ThrowsMessage<Error>("topic /cam/png: compressed image (format 'png', 8 bytes) is neither JPEG nor PNG"));
}

// A header that claims more pixels than the image's data can hold (image_header.h's bounds) is refused
// before a decoder allocates them: 30000x30000 on the 6x8 images is 900 MB to OpenCV.
TEST(RosMessages, CompressedImageClaimingMorePixelsThanItsDataHoldIsRefusedBeforeDecoding) {
  const OneMessage png_message("/cam/png"), jpeg_message("/cam/jpeg");
  RosCompressedImage png = decodeCompressedImage(*png_message), jpeg = decodeCompressedImage(*jpeg_message);
  std::vector<std::uint8_t> png_bytes(png.data.begin(), png.data.end()), jpeg_bytes(jpeg.data.begin(), jpeg.data.end());
  auto put16 = [](std::uint8_t* p, std::uint32_t v) { p[0] = v >> 8, p[1] = v & 0xff; };
  auto put32 = [](std::uint8_t* p, std::uint32_t v) {
    p[0] = v >> 24, p[1] = (v >> 16) & 0xff, p[2] = (v >> 8) & 0xff, p[3] = v & 0xff;
  };
  // PNG: IHDR's width and height (bytes 16..23), its CRC (29..32) made right again.
  put32(&png_bytes[16], 30000);
  put32(&png_bytes[20], 30000);
  put32(&png_bytes[29], static_cast<std::uint32_t>(crc32(0, &png_bytes[12], 17)));
  // JPEG: the baseline frame header (FF C0, length, precision, height, width).
  const std::uint8_t kSof0[] = {0xff, 0xc0};
  const std::size_t sof = static_cast<std::size_t>(
      std::search(jpeg_bytes.begin(), jpeg_bytes.end(), std::begin(kSof0), std::end(kSof0)) - jpeg_bytes.begin());
  ASSERT_LT(sof, jpeg_bytes.size());
  put16(&jpeg_bytes[sof + 5], 30000);
  put16(&jpeg_bytes[sof + 7], 30000);
  const std::size_t after_frame_header = sof + 2 + (jpeg_bytes[sof + 2] << 8 | jpeg_bytes[sof + 3]);
  png.data = png_bytes;
  jpeg.data = jpeg_bytes;
  rusage before{};
  getrusage(RUSAGE_SELF, &before);
  EXPECT_THAT([&] { compressedImageToMat(png, "/cam/png"); },
              testing::ThrowsMessage<Error>(testing::StartsWith(
                  "topic /cam/png: compressed image (format 'png', " + std::to_string(png_bytes.size()) +
                  " bytes): PNG claims 30000x30000 pixels, 900030000 bytes inflated, but its ")));
  EXPECT_THAT([&] { compressedImageToMat(jpeg, "/cam/jpeg"); },
              testing::ThrowsMessage<Error>(
                  "topic /cam/jpeg: compressed image (format 'mono8; jpeg compressed bgr8', " +
                  std::to_string(jpeg_bytes.size()) + " bytes): JPEG claims 30000x30000 pixels, more than its " +
                  std::to_string(jpeg_bytes.size() - after_frame_header) + " bytes of data can hold"));
  rusage after{};
  getrusage(RUSAGE_SELF, &after);
  EXPECT_LT(after.ru_maxrss - before.ru_maxrss, 256 * 1024) << "peak resident KiB grew";
}

TEST(RosMessages, CameraInfoFieldsAsWritten) {
  const RosCameraInfo info = decodeCameraInfo(*OneMessage("/cam/info"));
  EXPECT_EQ(info.frame_id, "cam1");
  EXPECT_EQ(info.width, 640u);
  EXPECT_EQ(info.height, 480u);
  EXPECT_EQ(info.distortion_model, "plumb_bob");
  EXPECT_EQ(info.D, (std::vector<double>{-0.1, 0.01, 0.001, -0.002, 0.0}));
  EXPECT_EQ(info.K, (std::array<double, 9>{400.0, 0, 320.5, 0, 401.0, 240.5, 0, 0, 1}));
  EXPECT_EQ(info.P, (std::array<double, 12>{390.0, 0, 321.0, -39.0, 0, 390.0, 241.0, 0, 0, 0, 1, 0}));
}

TEST(RosMessages, OdometryPoseStampedTransformAndTfPairGiveTheSamePose) {
  for (const char* topic : {"/odom", "/pose", "/tfs", "/tf"}) {
    const std::optional<RosPose> pose = decodePose(*OneMessage(topic), "world", "cam0");
    ASSERT_TRUE(pose.has_value()) << topic;
    EXPECT_EQ(pose->stamp_ns, 1700000000123456789) << topic;
    const Eigen::Isometry3d T = pose->transform();
    EXPECT_TRUE(T.translation().isApprox(Eigen::Vector3d(1.5, -2.25, 3.0), 1e-15)) << topic;
    // q = (0, 0, 0.6, 0.8): a rotation about z by 2 atan2(0.6, 0.8).
    EXPECT_NEAR(Eigen::AngleAxisd(T.linear()).angle(), 2.0 * std::atan2(0.6, 0.8), 1e-12) << topic;
  }
  EXPECT_FALSE(decodePose(*OneMessage("/tf"), "world", "imu").has_value());
  EXPECT_THAT([] { decodePose(*OneMessage("/cam/info")); },
              testing::ThrowsMessage<Error>(testing::StartsWith("topic /cam/info has type sensor_msgs/CameraInfo, not a "
                                                                "pose")));
  EXPECT_THAT(
      [] { decodeImage(*OneMessage("/cam/png")); },
      testing::ThrowsMessage<Error>("topic /cam/png has type sensor_msgs/CompressedImage, expected sensor_msgs/Image"));
}

TEST(RosMessages, MessageCutShortNamesTypeFieldTopicAndOffset) {
  const auto bag = openRecording(bagDir() / "messages.bag");
  RecordedMessage m;
  ASSERT_TRUE(bag->next({"/cam/info"}, m));
  m.data = m.data.first(60);  // the header (4 + 8 + 4 + 4), sizes, model (4 + 9), D (4 + 5 * 8) cut
  EXPECT_THAT([&] { decodeCameraInfo(m); },
              testing::ThrowsMessage<IoError>(testing::StartsWith(
                  "topic /cam/info, message at byte " + std::to_string(m.file_offset) + ": sensor_msgs/CameraInfo.D: ")));
}

}  // namespace
}  // namespace cenote::io
