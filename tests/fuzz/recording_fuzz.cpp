// Fuzzes the recording readers (io/bag/recording.h openRecording: ROS 1 bags, MCAP, ROS 2 .db3 bags)
// and the message decoders behind them (io/bag/ros_messages.h, ros_image.h), as a bag run reads a
// recording (pipeline/dataset/recording_dataset.cpp): every message in one pass, each image topic's
// header stamp and pixels, each CameraInfo, each pose and its transform.
// The first byte picks the layout, the rest is the recording:
//   bit 0 clear: one file, told apart by its first bytes (#ROSBAG, MCAP magic, SQLite header);
//   bit 0 set:   a ROS 2 bag folder: metadata.yaml up to the first NUL (none when empty), then a file
//                name up to the next NUL ("dive_0.db3", "dive_0.db3.zstd"), then that file's bytes;
//   bit 1 set:   only the topics of the types cenote reads are asked for (Recording::next's filter),
//                as a run asks for its image, CameraInfo and pose topics.
// A damaged message is the message's error and the pass goes on; a damaged recording ends the pass.
#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "common/error.h"
#include "io/bag/recording.h"
#include "io/bag/ros_image.h"
#include "io/bag/ros_messages.h"
#include "tests/fuzz/fuzz_input.h"

namespace {

using namespace cenote::io;

constexpr const char* kImage = "sensor_msgs/Image";
constexpr const char* kCompressed = "sensor_msgs/CompressedImage";
constexpr const char* kCameraInfo = "sensor_msgs/CameraInfo";

bool isRead(const std::string& type) {
  return type == kImage || type == kCompressed || type == kCameraInfo || isPoseType(type);
}

// The ROS 2 bag folder of an input whose first byte has bit 0 set; empty when the file name is not
// one name inside the folder.
std::filesystem::path writeBagFolder(const uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  const std::size_t yaml_end = std::min(bytes.find('\0'), bytes.size());
  const std::string yaml = bytes.substr(0, yaml_end);
  const std::size_t name_begin = std::min(yaml_end + 1, bytes.size());
  const std::size_t name_end = std::min(bytes.find('\0', name_begin), bytes.size());
  const std::string name = bytes.substr(name_begin, name_end - name_begin);
  if (name.find('/') != std::string::npos || name == "." || name == "..") return {};
  const std::filesystem::path folder = cenote::fuzz::freshInputFolder("bag");
  if (!yaml.empty()) std::ofstream(folder / "metadata.yaml", std::ios::binary) << yaml;
  if (!name.empty()) {
    const std::size_t file_begin = std::min(name_end + 1, bytes.size());
    std::ofstream(folder / name, std::ios::binary) << bytes.substr(file_begin);
  }
  return folder;
}

void decodeAsARunDoes(const RecordedMessage& m) {
  const std::string& type = m.topic->type;
  if (type == kImage || type == kCompressed) {
    (void)decodeHeaderStampNs(m);
    const cv::Mat pixels = type == kImage ? imageToMat(decodeImage(m), m.topic->name)
                                          : compressedImageToMat(decodeCompressedImage(m), m.topic->name);
    // The pipeline takes 8-bit grey or BGR, nothing else.
    if (pixels.empty() || (pixels.type() != CV_8UC1 && pixels.type() != CV_8UC3)) std::abort();
  } else if (type == kCameraInfo) {
    (void)decodeCameraInfo(m);
  } else if (isPoseType(type)) {
    const std::optional<RosPose> pose = decodePose(m);
    if (pose) (void)pose->transform();
    (void)decodePose(m, "world", "cam0");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const bool folder = (data[0] & 1) != 0;
  const bool filtered = (data[0] & 2) != 0;
  std::filesystem::path path;
  if (folder) {
    path = writeBagFolder(data + 1, size - 1);
    if (path.empty()) return 0;
  } else {
    path = cenote::fuzz::writeInputFile(data + 1, size - 1, "recording");
  }
  try {
    const std::unique_ptr<Recording> recording = openRecording(path);
    const std::vector<TopicInfo>& topics = recording->topics();
    std::vector<std::string> wanted;
    if (filtered) {
      for (const TopicInfo& t : topics)
        if (isRead(t.type)) wanted.push_back(t.name);
      if (wanted.empty()) return 0;
    }
    // Every topic is known after open (Recording::topics), and a run keeps pointers to them while it
    // reads (its left topic, the topic of each image held for pairing): the list never changes.
    const TopicInfo* const first = topics.data();
    const std::size_t count = topics.size();
    RecordedMessage m;
    while (recording->next(wanted, m)) {
      if (recording->topics().data() != first || recording->topics().size() != count) std::abort();
      if (m.topic == nullptr || m.topic < first || m.topic >= first + count) std::abort();
      try {
        decodeAsARunDoes(m);
      } catch (const cenote::Error&) {
      }
    }
    (void)recording->truncation();
    (void)recording->skipped();
    (void)recording->compression();
  } catch (const cenote::Error&) {
  }
  return 0;
}
