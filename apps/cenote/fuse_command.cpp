// `cenote fuse`: visibility-based fusion of a folder of depth maps with poses (pipeline/fusion/).
//   DEPTH_DIR/<timestamp>.depth.pfm   metres, +inf or 0 = none (required)
//   DEPTH_DIR/<timestamp>.conf.pfm    confidence (optional; 1 where absent)
//   COLOR_DIR/<timestamp>.png         left image (optional, with --color-dir)
//   trajectory                        TUM text, T_world_cam, matched by timestamp
// or the output folder of `cenote run --write-depth` (OUT or OUT/depth): its depth/frames.csv
// (pipeline/runner/depth_index.h) names each map and gives its time, intrinsics and pose, and the
// <name>.jpg beside each map colours the points; --trajectory and --intrinsics are then not given.
// A run with --fusion-views 1 writes the raw stereo maps, so fusing its folder is the run's fusion.
// Writes OUT/<timestamp>.depth.pfm and .conf.pfm per fused reference frame (optionally a 16-bit
// millimetre PNG and a colour-mapped preview) and one merged OUT/points.ply.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <vector>

#include "apps/cenote/commands.h"
#include "common/error.h"
#include "common/text_parse.h"
#include "common/yaml_section.h"
#include "common/pose_check.h"
#include "pipeline/fusion/fusion_window.h"
#include "pipeline/runner/depth_index.h"
#include "io/image/image_io.h"
#include "io/cloud/ply_io.h"
#include "io/trajectory/tum_trajectory.h"

namespace cenote::apps {
namespace {

namespace fs = std::filesystem;

constexpr const char* kDepthSuffix = ".depth.pfm";
constexpr const char* kConfidenceSuffix = ".conf.pfm";

struct FuseOptions {
  std::string depth_dir, color_dir, trajectory, intrinsics, config, out;
  // Unset (-1 / NaN) keeps the config's value; anything set is validated with the config.
  int views = -1;
  double eps = NAN, min_confidence = NAN, min_input_confidence = NAN, max_depth_m = NAN;
  std::string eps_mode;
  double pose_tolerance_s = 1e-3;
  bool png16 = false, preview = false;
};

struct InputFrame {
  std::string stamp;  // the file name's timestamp text (a run's frame name), reused for the outputs
  double t_s = 0.0;
  Eigen::Isometry3d T_world_cam;
};

// The frames of a depth folder, their intrinsics, and where their colour images are.
struct InputFolder {
  std::string depth_dir;
  std::vector<InputFrame> frames;
  Eigen::Matrix3d K;
  std::string color_dir, color_ext = ".png";  // color_dir empty: no colours
};

pipeline::FusionConfig makeConfig(const FuseOptions& o) {
  pipeline::FusionConfig config;
  if (!o.config.empty()) readConfigFile(o.config, "fusion", config);
  if (o.views != -1) config.num_views = o.views;
  if (!std::isnan(o.eps)) config.eps = o.eps;
  if (!o.eps_mode.empty()) config.support_radius = pipeline::parseSupportRadius(o.eps_mode);
  if (!std::isnan(o.min_confidence)) config.min_fused_confidence = o.min_confidence;
  if (!std::isnan(o.min_input_confidence)) config.min_input_confidence = o.min_input_confidence;
  if (!std::isnan(o.max_depth_m)) config.max_depth_m = o.max_depth_m;
  throwIfInvalid(config.validate(), "fusion");
  return config;
}

Eigen::Matrix3d parseIntrinsics(const std::string& text) {
  std::vector<double> values;
  std::string item;
  if (!parseNumberList(text, ',', values, &item))
    throw Error("--intrinsics '" + text + "': '" + item + "' is not a number");
  if (values.size() != 4) throw Error("--intrinsics '" + text + "': expected FX,FY,CX,CY (4 numbers)");
  Eigen::Matrix3d K;
  K << values[0], 0.0, values[2], 0.0, values[1], values[3], 0.0, 0.0, 1.0;
  checkIntrinsics(K, "--intrinsics");
  return K;
}

// Every <timestamp>.depth.pfm of the folder, in time order, each with its pose.
std::vector<InputFrame> listFrames(const FuseOptions& o, const io::TumTrajectory& trajectory) {
  std::vector<InputFrame> frames;
  for (const auto& entry : fs::directory_iterator(o.depth_dir)) {
    const std::string name = entry.path().filename().string();
    const size_t suffix = name.size() - std::string(kDepthSuffix).size();
    if (name.size() <= std::string(kDepthSuffix).size() || name.compare(suffix, std::string::npos, kDepthSuffix) != 0) {
      continue;
    }
    InputFrame frame;
    frame.stamp = name.substr(0, suffix);
    char* end = nullptr;
    frame.t_s = std::strtod(frame.stamp.c_str(), &end);
    if (*end != '\0' || !std::isfinite(frame.t_s)) {
      throw Error(entry.path().string() + ": file name must be <timestamp>" + kDepthSuffix + " with a number as timestamp");
    }
    frames.push_back(frame);
  }
  std::sort(frames.begin(), frames.end(), [](const InputFrame& a, const InputFrame& b) { return a.t_s < b.t_s; });
  for (size_t i = 1; i < frames.size(); ++i) {
    if (frames[i].t_s == frames[i - 1].t_s) {
      throw Error("--depth-dir " + o.depth_dir + ": " + frames[i - 1].stamp + " and " + frames[i].stamp +
                  " are the same time");
    }
  }
  for (InputFrame& frame : frames) {
    const auto pose = trajectory.lookup(frame.t_s, o.pose_tolerance_s);
    if (!pose) {
      std::ostringstream text;
      text << "no pose in " << o.trajectory << " within " << o.pose_tolerance_s << " s of t = " << frame.stamp << " ("
           << (fs::path(o.depth_dir) / (frame.stamp + kDepthSuffix)).string() << ")";
      throw Error(text.str());
    }
    frame.T_world_cam = pose->T_world_cam;
    checkPose(frame.T_world_cam, o.trajectory + ": pose at t = " + frame.stamp);
  }
  return frames;
}

std::string sizeText(const cv::Mat& m) { return std::to_string(m.cols) + "x" + std::to_string(m.rows); }

// The frames `cenote run --write-depth` wrote into `dir`, by its frames.csv, in time order.
InputFolder runFolder(const FuseOptions& o, const std::string& dir) {
  const std::string index = (fs::path(dir) / "frames.csv").string();
  if (!o.trajectory.empty() || !o.intrinsics.empty()) {
    throw Error("--depth-dir " + o.depth_dir + " is a `cenote run --write-depth` output (" + index +
                " gives each map's pose and intrinsics): give neither --trajectory nor --intrinsics");
  }
  InputFolder in{dir, {}, Eigen::Matrix3d::Identity(), dir, ".jpg"};
  const std::vector<pipeline::DepthIndexRow> rows = pipeline::readDepthIndex(index);
  if (rows.empty()) throw Error(index + ": no depth maps listed");
  in.K = rows.front().K;
  for (const pipeline::DepthIndexRow& row : rows) {
    if (row.K != in.K) throw Error(index + ": " + row.name + " has other intrinsics than " + rows.front().name);
    in.frames.push_back({row.name, row.t_s, row.T_world_cam});
  }
  std::stable_sort(in.frames.begin(), in.frames.end(),
                   [](const InputFrame& a, const InputFrame& b) { return a.t_s < b.t_s; });
  if (!o.color_dir.empty()) in.color_dir = o.color_dir, in.color_ext = ".png";
  return in;
}

// The depth folder as given: run's output folder (OUT or OUT/depth) when it holds frames.csv, else
// <timestamp>.depth.pfm files with --trajectory and --intrinsics.
InputFolder inputFolder(const FuseOptions& o) {
  if (!fs::is_directory(o.depth_dir)) throw Error("--depth-dir " + o.depth_dir + ": not a directory");
  for (const fs::path dir : {fs::path(o.depth_dir), fs::path(o.depth_dir) / "depth"}) {
    if (fs::exists(dir / "frames.csv")) return runFolder(o, dir.string());
  }
  if (o.trajectory.empty() || o.intrinsics.empty()) {
    throw Error("--depth-dir " + o.depth_dir + ": give --trajectory and --intrinsics (or the output folder of `cenote " +
                "run --write-depth`, whose depth/frames.csv gives them)");
  }
  const io::TumTrajectory trajectory = io::TumTrajectory::read(o.trajectory);
  return {o.depth_dir, listFrames(o, trajectory), parseIntrinsics(o.intrinsics), o.color_dir, ".png"};
}

pipeline::DepthFrame loadFrame(const InputFolder& folder, const InputFrame& in) {
  pipeline::DepthFrame frame;
  frame.t_s = in.t_s;
  frame.K = folder.K;
  frame.T_world_cam = in.T_world_cam;
  const std::string depth_path = (fs::path(folder.depth_dir) / (in.stamp + kDepthSuffix)).string();
  frame.depth = io::readPfm(depth_path);
  if (frame.depth.type() != CV_32FC1) throw Error(depth_path + ": depth must be a single-channel PFM");
  const std::string conf_path = (fs::path(folder.depth_dir) / (in.stamp + kConfidenceSuffix)).string();
  if (fs::exists(conf_path)) {
    frame.confidence = io::readPfm(conf_path);
    if (frame.confidence.type() != CV_32FC1 || frame.confidence.size() != frame.depth.size()) {
      throw Error(conf_path + " is " + sizeText(frame.confidence) + " (or not single-channel) but " + depth_path + " is " +
                  sizeText(frame.depth));
    }
  } else {
    frame.confidence = cv::Mat(frame.depth.size(), CV_32F, cv::Scalar(1.0f));
  }
  if (!folder.color_dir.empty()) {
    const std::string color_path = (fs::path(folder.color_dir) / (in.stamp + folder.color_ext)).string();
    frame.color = io::readImage(color_path, cv::IMREAD_COLOR);
    if (frame.color.size() != frame.depth.size()) {
      throw Error(color_path + " is " + sizeText(frame.color) + " but " + depth_path + " is " + sizeText(frame.depth));
    }
  }
  return frame;
}

void run(const FuseOptions& o) {
  const pipeline::FusionConfig config = makeConfig(o);
  const InputFolder folder = inputFolder(o);
  const std::vector<InputFrame>& frames = folder.frames;
  if (static_cast<int>(frames.size()) < config.num_views) {
    throw Error("--depth-dir " + o.depth_dir + ": " + std::to_string(frames.size()) + " depth maps (*" + kDepthSuffix +
                "), fusion of " + std::to_string(config.num_views) + " views needs at least that many");
  }
  std::error_code ec;
  fs::create_directories(o.out, ec);
  if (!fs::is_directory(o.out)) throw Error("--out " + o.out + ": cannot create directory");

  pipeline::FusionWindow window(config);
  io::PlyWriter ply((fs::path(o.out) / "points.ply").string());
  const int half = config.num_views / 2;
  int fused_frames = 0;
  double fusion_ms = 0.0;
  for (size_t i = 0; i < frames.size(); ++i) {
    const pipeline::DepthFrame frame = loadFrame(folder, frames[i]);
    const auto start = std::chrono::steady_clock::now();
    const pipeline::FusedFrame* fused;
    try {
      fused = window.push(frame);
    } catch (const Error& e) {
      throw Error(std::string(e.what()) + " (" + folder.depth_dir + "/" + frames[i].stamp + kDepthSuffix + ")");
    }
    fusion_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (!fused) continue;
    const std::string stamp = frames[i - half].stamp;
    const fs::path base = fs::path(o.out) / stamp;
    io::writePfm(base.string() + ".depth.pfm", fused->frame.depth);
    io::writePfm(base.string() + ".conf.pfm", fused->frame.confidence);
    if (o.png16) {
      const int clipped = io::writeDepthPng16(base.string() + ".depth.png", fused->frame.depth);
      if (clipped > 0) std::cerr << "warning: " << stamp << ": " << clipped << " depths above 65.535 m written as 0\n";
    }
    if (o.preview) io::writeImage(base.string() + ".preview.png", io::colorizeMap(fused->frame.depth));
    ply.append(fused->points);
    ++fused_frames;
  }
  ply.close();
  std::cout << "fused " << fused_frames << " of " << frames.size() << " frames (" << config.num_views << " views), "
            << ply.count() << " points written to " << (fs::path(o.out) / "points.ply").string() << ", fusion "
            << fusion_ms / std::max<size_t>(1, frames.size()) << " ms/frame\n";
}

}  // namespace

void registerFuseCommand(CLI::App& app) {
  auto options = std::make_shared<FuseOptions>();
  CLI::App* cmd = app.add_subcommand("fuse", "Fuse a folder of depth maps with poses into cleaner depth and points");
  cmd->add_option("--depth-dir", options->depth_dir,
                  "Folder of <timestamp>.depth.pfm (+ optional .conf.pfm), or a `cenote run --write-depth` output folder")
      ->required();
  cmd->add_option("--trajectory", options->trajectory,
                  "TUM trajectory (t tx ty tz qx qy qz qw), camera to world (not for a run's folder)");
  cmd->add_option("--intrinsics", options->intrinsics, "Pinhole intrinsics FX,FY,CX,CY in pixels (not for a run's folder)");
  cmd->add_option("--color-dir", options->color_dir, "Folder of <timestamp>.png left images (colours the points)");
  cmd->add_option("--config", options->config, "YAML file with a `fusion:` section");
  cmd->add_option("--views", options->views, "Views in the window, odd >= 3 (default 3)");
  cmd->add_option("--eps", options->eps, "Support radius: fraction of depth, or metres with --eps-mode absolute");
  cmd->add_option("--eps-mode", options->eps_mode, "relative (default) or absolute")
      ->check(CLI::IsMember({"relative", "absolute"}));
  cmd->add_option("--min-confidence", options->min_confidence, "C_thres: reject fused pixels below (default 0.5)");
  cmd->add_option("--min-input-confidence", options->min_input_confidence, "Ignore input pixels below (default 0)");
  cmd->add_option("--max-depth", options->max_depth_m, "Ignore input depths beyond, metres (default none)");
  cmd->add_option("--pose-tolerance", options->pose_tolerance_s, "Largest time difference to a pose, s")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--png16", options->png16, "Also write <timestamp>.depth.png (16-bit millimetres)");
  cmd->add_flag("--preview", options->preview, "Also write <timestamp>.preview.png (colour-mapped depth)");
  cmd->add_option("--out", options->out, "Output folder")->required();
  cmd->callback([options] { run(*options); });
}

}  // namespace cenote::apps
