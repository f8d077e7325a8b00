// `cenote stereo`: disparity, confidence and depth of one stereo pair.
#include <algorithm>
#include <chrono>
#include <iostream>
#include <memory>
#include <utility>
#include <vector>

#include "apps/cenote/commands.h"
#include "apps/cenote/dataset_source.h"
#include "apps/cenote/subcommand.h"
#include "common/error.h"
#include "common/median.h"
#include "common/yaml_section.h"
#include "pipeline/calibration/rectifier.h"
#include "io/image/image_io.h"
#include "pipeline/stereo/stereo_matcher.h"

namespace cenote::apps {
namespace {

struct StereoOptions {
  std::string left, right, calib, config;
  std::string dataset, format = "auto", left_topic, right_topic;  // a dataset source instead of two images
  int frame = -1;
  std::string out_disparity, out_confidence, out_depth, out_preview;
  std::string cost, search;
  int disparities = 0, min_disparity = -1, window = 0, paths = 0, repeat = 0;
  bool lr_check = false;
  double focal_px = 0.0, baseline_m = 0.0;
};

pipeline::StereoConfig makeConfig(const StereoOptions& o) {
  pipeline::StereoConfig config;
  if (!o.config.empty()) readConfigFile(o.config, "stereo", config);
  if (!o.cost.empty()) {
    config.cost = pipeline::parseMatchingCost(o.cost);
    if (o.window == 0 && config.cost == pipeline::MatchingCost::kCensus) config.window_px = 5;
  }
  if (o.disparities > 0) config.num_disparities = o.disparities;
  if (o.min_disparity >= 0) config.min_disparity_px = o.min_disparity;
  if (o.window > 0) config.window_px = o.window;
  if (o.paths > 0) config.num_paths = o.paths;
  if (!o.search.empty()) config.search = pipeline::parseSearchMode(o.search);
  if (o.lr_check) config.lr_check = true;
  return config;
}

// The pair to match: two image files, or frame --frame of --dataset (images as recorded).
pipeline::StereoFrame readPair(const StereoOptions& o, std::unique_ptr<pipeline::StereoDataset>& dataset) {
  if (o.dataset.empty()) {
    if (o.left.empty() || o.right.empty()) throw Error("stereo: give --left and --right images, or --dataset and --frame");
    if (o.frame >= 0) throw Error("stereo: --frame needs --dataset");
    for (const auto& [flag, value] : {std::pair{"--left-topic", &o.left_topic}, std::pair{"--right-topic", &o.right_topic}})
      if (!value->empty()) throw Error(std::string("stereo: ") + flag + " needs --dataset");
    pipeline::StereoFrame frame;
    frame.left = io::readImage(o.left, cv::IMREAD_COLOR);
    frame.right = io::readImage(o.right, cv::IMREAD_COLOR);
    return frame;
  }
  if (!o.left.empty() || !o.right.empty()) throw Error("stereo: give --left/--right images or --dataset, not both");
  if (o.frame < 0) throw Error("stereo: --dataset needs --frame N (the N-th stereo pair, from 0)");
  // A recording takes --calib in place of its CameraInfo topics; a folder's own calibration is replaced below.
  const DatasetSource source{o.dataset,
                             o.format,
                             o.left_topic,
                             o.right_topic,
                             o.calib,
                             o.config,
                             {{"--left-topic", o.left_topic}, {"--right-topic", o.right_topic}}};
  dataset = openDatasetSource(source);
  return loadNthFrame(*dataset, static_cast<size_t>(o.frame), o.dataset);
}

void run(const StereoOptions& o) {
  pipeline::StereoMatcher matcher(makeConfig(o));
  std::unique_ptr<pipeline::StereoDataset> dataset;
  const pipeline::StereoFrame frame = readPair(o, dataset);
  const std::string left_name = o.dataset.empty() ? o.left : "left image of frame " + std::to_string(o.frame);
  const std::string right_name = o.dataset.empty() ? o.right : "right image of frame " + std::to_string(o.frame);
  double focal_px = o.focal_px, baseline_m = o.baseline_m;
  cv::Mat left = frame.left, right = frame.right;
  if (!o.calib.empty() || dataset) {
    const pipeline::Rectifier rectifier(o.calib.empty() ? dataset->calibration()
                                                        : pipeline::readCalibrationFile(o.calib, frame.left.size()));
    const pipeline::RectifiedPair pair = rectifier.rectify(frame);
    left = pair.left;
    right = pair.right;
    focal_px = pair.geometry.fx;
    baseline_m = pair.geometry.baseline_m;
  } else if (left.size() != right.size()) {
    throw Error("stereo: right image " + right_name + " is " + std::to_string(right.cols) + "x" +
                std::to_string(right.rows) + " but left image " + left_name + " is " + std::to_string(left.cols) + "x" +
                std::to_string(left.rows));
  }
  if (!o.out_depth.empty() && !(focal_px > 0.0 && baseline_m > 0.0)) {
    throw Error("stereo: --out-depth needs --calib (or --focal-px and --baseline-m)");
  }

  pipeline::DisparityMap result = matcher.match(left, right);
  if (o.repeat > 0) {
    std::vector<double> ms;
    for (int i = 0; i < o.repeat; ++i) {
      result = {};  // released first, as a consumer would: the matcher then reuses its memory
      const auto start = std::chrono::steady_clock::now();
      result = matcher.match(left, right);
      ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    }
    std::cout << "stereo_ms_median=" << median(ms) << "\n";
  }

  io::writePfm(o.out_disparity, result.disparity);
  if (!o.out_confidence.empty()) io::writePfm(o.out_confidence, result.confidence);
  if (!o.out_depth.empty()) {
    io::writePfm(o.out_depth, pipeline::disparityToDepth(result.disparity, focal_px, baseline_m));
  }
  if (!o.out_preview.empty()) {
    const auto& c = matcher.config();
    io::writeImage(o.out_preview,
                   io::colorizeMap(result.disparity, c.min_disparity_px, c.min_disparity_px + c.num_disparities));
  }
  const int valid = cv::countNonZero(result.confidence > 0.0f);
  std::cout << "disparity " << left.cols << "x" << left.rows << ", valid "
            << (100.0 * valid / std::max(1, left.cols * left.rows)) << " %, written to " << o.out_disparity << "\n";
}

}  // namespace

void registerStereoCommand(CLI::App& app) {
  const auto [cmd, options] = addSubcommand<StereoOptions>(app, "stereo",
                                                           "Disparity, confidence and depth of one stereo pair", run);
  cmd->add_option("--left", options->left, "Left image");
  cmd->add_option("--right", options->right, "Right image");
  cmd->add_option("--dataset", options->dataset,
                  "Instead of --left/--right: a dataset as `cenote run` reads it (EuRoC, KITTI, the paper's layout, "
                  "ROS 1 bag, MCAP, ROS 2 bag), its pair --frame rectified with its calibration (or --calib)");
  cmd->add_option("--format", options->format, "Dataset layout (auto: a file or a ROS 2 bag folder is a recording)")
      ->check(CLI::IsMember({"auto", "euroc", "kitti", "paper", "bag"}));
  cmd->add_option("--frame", options->frame, "Dataset: the stereo pair to match, from 0")->check(CLI::NonNegativeNumber);
  cmd->add_option("--left-topic", options->left_topic,
                  "Recording: left image topic (default: the first rig preset of bag.rigs found)");
  cmd->add_option("--right-topic", options->right_topic, "Recording: right image topic");
  cmd->add_option("--calib,--calibration", options->calib,
                  "Stereo calibration: OpenCV YAML, EuRoC cam0/sensor.yaml (+ cam1), KITTI calib.txt, the paper's "
                  "intrinsics.yaml (raw pairs are rectified); with --dataset it replaces the dataset's (a "
                  "recording's CameraInfo topics)");
  cmd->add_option("--config", options->config, "YAML file with a `stereo:` section (and `bag:` for a recording)");
  cmd->add_option("--disparities", options->disparities, "Number of disparities (multiple of 16)");
  cmd->add_option("--min-disparity", options->min_disparity, "First disparity searched");
  cmd->add_option("--cost", options->cost, "Matching cost")->check(CLI::IsMember({"sad", "census"}));
  cmd->add_option("--window", options->window, "Cost window side (SAD 1..9 odd, census 3 or 5)");
  cmd->add_option("--paths", options->paths, "SGM paths")->check(CLI::IsMember({4, 8}));
  cmd->add_option("--search", options->search,
                  "Disparities searched: full range, or a band around a match of the shrunk pair")
      ->check(CLI::IsMember({"full", "band"}));
  cmd->add_flag("--lr-check", options->lr_check, "Left-right consistency check");
  cmd->add_option("--focal-px", options->focal_px, "Focal length for depth without --calib");
  cmd->add_option("--baseline-m", options->baseline_m, "Baseline for depth without --calib");
  cmd->add_option("--out-disparity", options->out_disparity, "Disparity PFM (+inf = invalid)")->required();
  cmd->add_option("--out-confidence", options->out_confidence, "PKRN confidence PFM");
  cmd->add_option("--out-depth", options->out_depth, "Depth PFM in metres (+inf = none)");
  cmd->add_option("--out-preview", options->out_preview, "Colour-mapped disparity PNG");
  cmd->add_option("--repeat", options->repeat, "Match N more times and print stereo_ms_median")
      ->check(CLI::NonNegativeNumber);
}

}  // namespace cenote::apps
