#include "eval/trajectory/trajectory_io.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/enum_names.h"
#include "common/error.h"
#include "io/trajectory/trajectory.h"

namespace cenote::eval {
namespace {

namespace fs = std::filesystem;

bool isNumber(const std::string& word, double& value) {
  char* end = nullptr;
  value = std::strtod(word.c_str(), &end);
  return end != word.c_str() && *end == '\0';
}

// A COLMAP image line: 9 numbers and a name (names may contain spaces).
bool looksLikeColmapImage(const std::string& line) {
  std::istringstream words(line);
  std::string word;
  double v = 0.0;
  for (int i = 0; i < 9; ++i) {
    if (!(words >> word) || !isNumber(word, v)) return false;
  }
  return static_cast<bool>(words >> word) && !isNumber(word, v);
}

}  // namespace

constexpr EnumName<TrajectoryFileFormat> kFileFormatNames[] = {
    {TrajectoryFileFormat::kAuto, "auto"},     {TrajectoryFileFormat::kTum, "tum"},
    {TrajectoryFileFormat::kEuroc, "euroc"},   {TrajectoryFileFormat::kKitti, "kitti"},
    {TrajectoryFileFormat::kColmap, "colmap"}, {TrajectoryFileFormat::kOkvis, "okvis"}};

TrajectoryFileFormat parseTrajectoryFileFormat(const std::string& name) {
  return parseEnumName(kFileFormatNames, name, "trajectory format '" + name + "'");
}

const char* toString(TrajectoryFileFormat format) { return enumName(kFileFormatNames, format); }

TrajectoryFileFormat detectTrajectoryFileFormat(const std::string& path) {
  std::ifstream in(path);
  if (!in) throwReadError(path, "not readable", "trajectory ");
  if (fs::path(path).filename() == "images.txt") return TrajectoryFileFormat::kColmap;
  std::string line;
  while (std::getline(in, line)) {
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    if (looksLikeColmapImage(line)) return TrajectoryFileFormat::kColmap;
    break;
  }
  switch (io::detectTrajectoryFormat(path)) {
    case io::TrajectoryFormat::kTum:
    case io::TrajectoryFormat::kOpenVins: return TrajectoryFileFormat::kTum;
    case io::TrajectoryFormat::kEuroc: return TrajectoryFileFormat::kEuroc;
    case io::TrajectoryFormat::kOkvis: return TrajectoryFileFormat::kOkvis;
    case io::TrajectoryFormat::kKitti: return TrajectoryFileFormat::kKitti;
  }
  return TrajectoryFileFormat::kTum;
}

std::vector<io::StampedPose> readColmapImagesTxt(const std::string& path) {
  std::ifstream in(path);
  if (!in) throwReadError(path, "not readable");
  std::vector<io::StampedPose> poses;
  std::vector<std::string> names;
  std::string line;
  int line_number = 0;
  bool expect_points = false;
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (expect_points) {  // the 2-D points of the image above; may be empty
      expect_points = false;
      continue;
    }
    const size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    const std::string where = path + ":" + std::to_string(line_number) + ": ";
    std::istringstream words(line);
    double v[9];
    std::string word;
    for (int i = 0; i < 9; ++i) {
      if (!(words >> word) || !isNumber(word, v[i])) {
        throw Error(where + "expected 'IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME' (COLMAP images.txt)");
      }
      if (!std::isfinite(v[i])) throw Error(where + "non-finite value '" + word + "'");
    }
    std::string name;
    std::getline(words >> std::ws, name);
    if (name.empty()) throw Error(where + "image line has no NAME");
    Eigen::Quaterniond q(v[1], v[2], v[3], v[4]);
    if (std::abs(q.norm() - 1.0) > io::kQuaternionNormTolerance) {
      std::ostringstream text;
      text << where << "quaternion (QW QX QY QZ) has norm " << q.norm() << ", must be 1";
      throw Error(text.str());
    }
    const std::string stem = fs::path(name).stem().string();
    double t_s = 0.0;
    if (!isNumber(stem, t_s) || !std::isfinite(t_s)) {
      throw Error(where + "image name '" + name + "' is not a timestamp: name the images <seconds>.<ext> to evaluate");
    }
    Eigen::Isometry3d T_cam_world = Eigen::Isometry3d::Identity();
    T_cam_world.linear() = q.normalized().toRotationMatrix();
    T_cam_world.translation() = Eigen::Vector3d(v[5], v[6], v[7]);
    poses.push_back({t_s, T_cam_world.inverse()});
    names.push_back(name);
    expect_points = true;
  }
  std::vector<size_t> order(poses.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return poses[a].t_s < poses[b].t_s; });
  std::vector<io::StampedPose> sorted;
  for (size_t k = 0; k < order.size(); ++k) {
    if (k > 0 && poses[order[k]].t_s == poses[order[k - 1]].t_s) {
      throw Error(path + ": images '" + names[order[k - 1]] + "' and '" + names[order[k]] + "' have the same timestamp");
    }
    sorted.push_back(poses[order[k]]);
  }
  return sorted;
}

std::vector<io::StampedPose> readTrajectoryFile(const std::string& path, TrajectoryFileFormat format,
                                                const std::string& kitti_times) {
  if (format == TrajectoryFileFormat::kAuto) format = detectTrajectoryFileFormat(path);
  if (!kitti_times.empty() && format != TrajectoryFileFormat::kKitti) {
    throw Error("a times file (" + kitti_times + ") applies to KITTI trajectories only, " + path + " is " +
                toString(format));
  }
  std::vector<io::StampedPose> poses;
  switch (format) {
    case TrajectoryFileFormat::kColmap: poses = readColmapImagesTxt(path); break;
    case TrajectoryFileFormat::kTum: poses = io::Trajectory::read(path, io::TrajectoryFormat::kTum).poses(); break;
    case TrajectoryFileFormat::kEuroc: poses = io::Trajectory::read(path, io::TrajectoryFormat::kEuroc).poses(); break;
    case TrajectoryFileFormat::kOkvis: poses = io::Trajectory::read(path, io::TrajectoryFormat::kOkvis).poses(); break;
    case TrajectoryFileFormat::kKitti:
      poses = io::Trajectory::read(path, io::TrajectoryFormat::kKitti, kitti_times).poses();
      break;
    case TrajectoryFileFormat::kAuto: break;
  }
  if (poses.empty()) throw Error(path + ": no pose in the file (" + std::string(toString(format)) + ")");
  return poses;
}

}  // namespace cenote::eval
