#include "apps/cenote/dataset_source.h"

#include <filesystem>

#include "common/error.h"
#include "common/yaml_section.h"
#include "io/bag/recording.h"
#include "pipeline/dataset/recording_dataset.h"

namespace cenote::apps {
namespace {

// The `bag:` section of the configuration file (defaults without one).
pipeline::RecordingConfig bagConfig(const std::string& config_path) {
  pipeline::RecordingConfig config;
  if (config_path.empty()) return config;
  YamlSection root(loadYamlFile(config_path), "", config_path);
  YamlSection section = root.section("bag");
  config.read(section);
  section.finish();
  return config;
}

}  // namespace

bool isRecording(const DatasetSource& source) {
  return source.format == "bag" ||
         (source.format == "auto" && (std::filesystem::is_regular_file(source.path) || io::isRos2BagFolder(source.path)));
}

std::unique_ptr<pipeline::StereoDataset> openDatasetSource(const DatasetSource& source) {
  if (isRecording(source)) {
    return std::make_unique<pipeline::RecordingDataset>(
        source.path, pipeline::RecordingTopics{source.left_topic, source.right_topic, source.calibration, "", ""},
        bagConfig(source.config));
  }
  for (const auto& [flag, value] : source.recording_options) {
    if (!value.empty()) {
      throw Error(flag + " is for recordings (.bag, .mcap, a ROS 2 bag); " + source.path + " is a folder");
    }
  }
  return pipeline::openDataset(source.path, pipeline::parseDatasetFormat(source.format));
}

pipeline::StereoFrame loadNthFrame(const pipeline::StereoDataset& dataset, size_t index, const std::string& name) {
  const std::unique_ptr<pipeline::FrameCursor> cursor = dataset.frames();
  size_t count = 0;
  while (cursor->next()) {
    if (count == index) return cursor->load();
    ++count;
  }
  throw Error("--frame " + std::to_string(index) + ": " + name + " has " + std::to_string(count) +
              " stereo pairs (frames 0.." + (count > 0 ? std::to_string(count - 1) : std::string("none")) + ")");
}

}  // namespace cenote::apps
