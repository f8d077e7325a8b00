#include "pipeline/dataset/kitti_dataset.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "common/error.h"
#include "io/image/image_io.h"

namespace cenote::pipeline {
namespace fs = std::filesystem;
namespace {

std::string frameStem(size_t index) {
  char name[32];
  std::snprintf(name, sizeof(name), "%06zu", index);
  return name;
}

// Row `key` of calib.txt as a 3x4 matrix.
cv::Matx34d projectionRow(const std::string& calib, const std::string& key) {
  std::ifstream in(calib);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(key + ":", 0) != 0) continue;
    std::istringstream values(line.substr(key.size() + 1));
    cv::Matx34d P;
    for (int i = 0; i < 12; ++i) {
      if (!(values >> P.val[i])) throw Error(calib + ": row " + key + " must have 12 numbers");
    }
    return P;
  }
  throw Error(calib + ": missing row " + key);
}

}  // namespace

KittiDataset::KittiDataset(const std::string& sequence_dir) : dir_(sequence_dir) {
  const fs::path dir(sequence_dir);
  const bool colour = fs::exists(dir / "image_2") && fs::exists(dir / "image_3");
  if (!colour && !(fs::exists(dir / "image_0") && fs::exists(dir / "image_1"))) {
    throw Error("KITTI " + sequence_dir + ": missing image_2/image_3 (or image_0/image_1)");
  }
  left_dir_ = (dir / (colour ? "image_2" : "image_0")).string();
  right_dir_ = (dir / (colour ? "image_3" : "image_1")).string();
  const std::string times = (dir / "times.txt").string();
  std::ifstream in(times);
  if (!in) throw Error("KITTI " + sequence_dir + ": missing times.txt");
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    char* end = nullptr;
    const double t = std::strtod(line.c_str(), &end);
    if (end == line.c_str()) throw Error(times + ":" + std::to_string(number) + ": not a timestamp");
    times_.push_back(t);
  }
  const std::string calib = (dir / "calib.txt").string();
  if (!fs::exists(calib)) throw Error("KITTI " + sequence_dir + ": missing calib.txt");
  const cv::Mat first = io::readImage((fs::path(left_dir_) / (frameStem(0) + ".png")).string(), cv::IMREAD_UNCHANGED);
  const std::string left_key = colour ? "P2" : "P0", right_key = colour ? "P3" : "P1";
  calibration_ = readKittiCalibration(calib, first.size(), left_key, right_key);
  // P_i = K [I | t_i] maps camera-0 points into camera i: the camera sits at -t_i in camera 0.
  const cv::Matx34d P = projectionRow(calib, left_key);
  const Eigen::Vector3d t(P(0, 3), P(1, 3), P(2, 3));
  Eigen::Matrix3d K;
  K << P(0, 0), P(0, 1), P(0, 2), P(1, 0), P(1, 1), P(1, 2), P(2, 0), P(2, 1), P(2, 2);
  T_body_cam_.translation() = -(K.inverse() * t);
}

std::string KittiDataset::frameName(size_t index) const { return frameStem(index); }

StereoFrame KittiDataset::load(size_t index) const {
  return readStereoFrame(times_.at(index), (fs::path(left_dir_) / (frameStem(index) + ".png")).string(),
                         (fs::path(right_dir_) / (frameStem(index) + ".png")).string());
}

std::optional<TrajectorySource> KittiDataset::defaultTrajectory() const {
  // dataset/sequences/<seq> -> dataset/poses/<seq>.txt
  const fs::path dir = fs::path(dir_).lexically_normal();
  const fs::path seq = dir.filename().empty() ? dir.parent_path().filename() : dir.filename();
  const fs::path poses = dir.parent_path().parent_path() / "poses" / (seq.string() + ".txt");
  if (!fs::exists(poses)) return std::nullopt;
  return trajectoryFile(poses.string(), io::TrajectoryFormat::kKitti);
}

TrajectorySource KittiDataset::trajectoryFile(const std::string& path, io::TrajectoryFormat format) const {
  TrajectorySource source = StereoDataset::trajectoryFile(path, format);
  if (format == io::TrajectoryFormat::kKitti) {
    source.kitti_times = (fs::path(dir_) / "times.txt").string();
    source.describes_body = true;  // camera 0, which T_body_cam takes to the left camera
    source.frame_assumed = false;
  }
  return source;
}

std::string KittiDataset::describe() const {
  return "KITTI " + dir_ + ": " + std::to_string(times_.size()) + " stereo frames";
}

}  // namespace cenote::pipeline
