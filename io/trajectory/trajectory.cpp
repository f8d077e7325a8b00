#include "io/trajectory/trajectory.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "common/enum_names.h"
#include "common/error.h"
#include "common/pose_check.h"
#include "io/trajectory/vio_trajectory.h"

namespace cenote::io {
namespace {

// Numbers of one line separated by `separator` (spaces always count); false if a word is not a
// number.
bool parseNumbers(const std::string& line, char separator, std::vector<double>& out) {
  out.clear();
  std::string text = line;
  if (separator != ' ') std::replace(text.begin(), text.end(), separator, ' ');
  std::istringstream words(text);
  std::string word;
  while (words >> word) {
    char* end = nullptr;
    const double v = std::strtod(word.c_str(), &end);
    if (end == word.c_str() || *end != '\0') return false;
    out.push_back(v);
  }
  return true;
}

bool isDataLine(const std::string& line) {
  const size_t first = line.find_first_not_of(" \t\r");
  return first != std::string::npos && line[first] != '#' && std::isalpha(static_cast<unsigned char>(line[first])) == 0;
}

// Calls parse(numbers, where, index) for each data line of `in` (the file at `path`): the line's
// numbers (separated by `separator`; none when a word is not a number), "<path>:<line>: " for its
// errors, and the number of poses before it. @return the poses that `parse` returned, in file order.
template <typename Parse>
std::vector<StampedPose> readPoseLines(std::ifstream& in, const std::string& path, char separator, Parse parse) {
  std::vector<StampedPose> poses;
  std::string line;
  std::vector<double> v;
  for (int number = 1; std::getline(in, line); ++number) {
    if (!isDataLine(line)) continue;
    if (!parseNumbers(line, separator, v)) v.clear();
    poses.push_back(parse(v, path + ":" + std::to_string(number) + ": ", poses.size()));
  }
  return poses;
}

std::ifstream openOrThrow(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error("cannot read trajectory " + path + ": no such file or not readable");
  return in;
}

Trajectory readEuroc(const std::string& path) {
  std::ifstream in = openOrThrow(path);
  const auto parse = [](const std::vector<double>& v, const std::string& where, size_t) {
    if (v.size() < 8) throw Error(where + "expected 't_ns, px, py, pz, qw, qx, qy, qz' (comma separated)");
    const Eigen::Quaterniond q(v[4], v[5], v[6], v[7]);
    if (!std::isfinite(q.norm()) || std::abs(q.norm() - 1.0) > kQuaternionNormTolerance) {
      throw Error(where + "quaternion (qw qx qy qz) is not of unit norm");
    }
    StampedPose pose;
    pose.t_s = v[0] * 1e-9;
    pose.T_world_cam.linear() = q.normalized().toRotationMatrix();
    pose.T_world_cam.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    return pose;
  };
  return Trajectory(readPoseLines(in, path, ',', parse), path);
}

Trajectory readKitti(const std::string& path, const std::string& times_path) {
  std::ifstream in = openOrThrow(path);
  std::vector<double> times;
  if (!times_path.empty()) {
    std::ifstream t(times_path);
    if (!t) throw Error("cannot read KITTI times " + times_path + ": no such file");
    double value;
    while (t >> value) times.push_back(value);
  }
  const auto parse = [&](const std::vector<double>& v, const std::string& where, size_t index) {
    if (v.size() != 12) throw Error(where + "expected 12 numbers (a 3x4 [R | t] row-major)");
    if (!times_path.empty() && index >= times.size()) {
      throw Error(times_path + ": has " + std::to_string(times.size()) + " times but " + path + " has more poses");
    }
    StampedPose pose;
    pose.t_s = times_path.empty() ? static_cast<double>(index) * 0.1 : times[index];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) pose.T_world_cam.linear()(r, c) = v[r * 4 + c];
      pose.T_world_cam.translation()(r) = v[r * 4 + 3];
    }
    return pose;
  };
  return Trajectory(readPoseLines(in, path, ' ', parse), path);
}

}  // namespace

Trajectory::Trajectory(std::vector<StampedPose> poses, std::string name)
    : poses_(std::move(poses)), name_(std::move(name)) {
  for (size_t i = 0; i < poses_.size(); ++i) {
    std::ostringstream what;
    what.precision(17);
    what << name_ << ": pose " << i << " (t = " << poses_[i].t_s << " s)";
    if (!std::isfinite(poses_[i].t_s)) throw Error(what.str() + ": timestamp is not finite");
    checkPose(poses_[i].T_world_cam, what.str());
    if (i > 0 && !(poses_[i].t_s > poses_[i - 1].t_s))
      throw Error(what.str() + ": timestamp is not after the previous one");
  }
}

Trajectory Trajectory::read(const std::string& path, TrajectoryFormat format, const std::string& kitti_times) {
  switch (format) {
    case TrajectoryFormat::kTum:
    case TrajectoryFormat::kOpenVins: {
      const TumTrajectory tum = TumTrajectory::read(path);
      return Trajectory(tum.poses(), path);
    }
    case TrajectoryFormat::kEuroc: return readEuroc(path);
    case TrajectoryFormat::kKitti: return readKitti(path, kitti_times);
    case TrajectoryFormat::kOkvis: return readOkvisCsv(path);
  }
  throw Error("unknown trajectory format");
}

std::optional<Eigen::Isometry3d> Trajectory::poseAt(double t_s, double max_gap_s) const {
  if (poses_.empty() || !std::isfinite(t_s)) return std::nullopt;
  constexpr double kSameTime = 1e-6;
  const auto after = std::lower_bound(poses_.begin(), poses_.end(), t_s,
                                      [](const StampedPose& p, double t) { return p.t_s < t; });
  if (after != poses_.end() && after->t_s - t_s <= kSameTime) return after->T_world_cam;
  if (after != poses_.begin() && t_s - std::prev(after)->t_s <= kSameTime) return std::prev(after)->T_world_cam;
  if (after == poses_.end() || after == poses_.begin()) return std::nullopt;
  const StampedPose& a = *std::prev(after);
  const StampedPose& b = *after;
  // The gap is compared with kSameTime of slack: a 10 Hz stream stamped in seconds since 1970 has
  // gaps of 0.1 s only to within 1e-7 s (the spacing of doubles near 1.7e9), so a plain `>` would
  // reject about half of the gaps that are exactly max_gap_s.
  if (b.t_s - a.t_s > max_gap_s + kSameTime) return std::nullopt;
  const double s = (t_s - a.t_s) / (b.t_s - a.t_s);
  const Eigen::Quaterniond qa(a.T_world_cam.linear()), qb(b.T_world_cam.linear());
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = qa.slerp(s, qb).toRotationMatrix();
  pose.translation() = (1.0 - s) * a.T_world_cam.translation() + s * b.T_world_cam.translation();
  return pose;
}

Trajectory Trajectory::transformedBy(const Eigen::Isometry3d& T_x_y) const {
  Trajectory out = *this;
  for (StampedPose& p : out.poses_) p.T_world_cam = p.T_world_cam * T_x_y;
  return out;
}

constexpr EnumName<TrajectoryFormat> kFormatNames[] = {
    {TrajectoryFormat::kTum, "tum"},     {TrajectoryFormat::kEuroc, "euroc"}, {TrajectoryFormat::kKitti, "kitti"},
    {TrajectoryFormat::kOkvis, "okvis"}, {TrajectoryFormat::kOkvis, "svin2"}, {TrajectoryFormat::kOpenVins, "openvins"}};

const char* toString(TrajectoryFormat format) { return enumName(kFormatNames, format); }

TrajectoryFormat parseTrajectoryFormat(const std::string& name) {
  return parseEnumName(kFormatNames, name, "trajectory format '" + name + "'");
}

bool describesBody(TrajectoryFormat format) {
  return format == TrajectoryFormat::kEuroc || format == TrajectoryFormat::kOkvis || format == TrajectoryFormat::kOpenVins;
}

TrajectoryFormat detectTrajectoryFormat(const std::string& path) {
  std::ifstream in = openOrThrow(path);
  std::string line;
  std::vector<double> v;
  while (std::getline(in, line)) {
    if (line.find("p_WS_W_x") != std::string::npos) return TrajectoryFormat::kOkvis;
    if (!isDataLine(line)) continue;
    if (line.find(',') != std::string::npos) return TrajectoryFormat::kEuroc;
    if (parseNumbers(line, ' ', v) && v.size() == 8) return TrajectoryFormat::kTum;
    if (parseNumbers(line, ' ', v) && v.size() == 12) return TrajectoryFormat::kKitti;
    break;
  }
  throw Error(path + ": cannot tell the trajectory format (TUM: 8 numbers a line, KITTI: 12, EuRoC: CSV, OKVIS: CSV "
                     "with a p_WS_W_x header)");
}

}  // namespace cenote::io
