// dataset_source.h: the `--dataset` source of a command (`cenote run`, `cenote stereo`): a folder
// (EuRoC, KITTI, the paper's layout: pipeline::openDataset) or a recording (ROS 1 bag, MCAP, a ROS 2
// bag folder or .db3: pipeline::RecordingDataset) with its topics, opened the same way for every command.
// Threads: at start-up only.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "pipeline/dataset/stereo_dataset.h"

namespace cenote::apps {

struct DatasetSource {
  std::string path;
  std::string format = "auto";          // "auto", "euroc", "kitti", "paper" or "bag"
  std::string left_topic, right_topic;  // recordings; both empty: the first rig preset of bag.rigs found
  std::string calibration;              // recordings: a calibration file; empty: the CameraInfo topics
  std::string config;                   // a YAML file whose `bag:` section configures recordings
  // The recording-only options as the command spells them, with their values: set on a folder, an error.
  std::vector<std::pair<std::string, std::string>> recording_options;
};

// True when `source` is read as a recording: --format bag, or auto and a file or a ROS 2 bag folder.
bool isRecording(const DatasetSource& source);

// Opens the source. @throws cenote::Error naming the option when a recording-only option is set for a
// folder, and whatever openDataset / RecordingDataset throw.
std::unique_ptr<pipeline::StereoDataset> openDatasetSource(const DatasetSource& source);

// Frame `index` (from 0) of the dataset, reached front to back (a recording has no index).
// @throws cenote::Error naming the dataset (`name`) and its number of stereo pairs when it has no such frame.
pipeline::StereoFrame loadNthFrame(const pipeline::StereoDataset& dataset, size_t index, const std::string& name);

}  // namespace cenote::apps
