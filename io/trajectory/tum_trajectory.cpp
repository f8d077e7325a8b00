#include "io/trajectory/tum_trajectory.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "common/error.h"

namespace cenote::io {

TumTrajectory TumTrajectory::read(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error("cannot read trajectory " + path + ": no such file or not readable");
  return parse(in, path);
}

namespace {

// Whether `row` starts with a word rather than a number (strtod's "nan" and "inf" are numbers).
bool isColumnNames(const std::string& row) {
  if (row.empty() || !std::isalpha(static_cast<unsigned char>(row[0]))) return false;
  std::string head = row.substr(0, 3);
  for (char& c : head) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return head != "nan" && head != "inf";
}

}  // namespace

TumTrajectory TumTrajectory::parse(std::istream& in, const std::string& name) {
  TumTrajectory trajectory;
  std::string line;
  int line_number = 0;
  bool nanoseconds = false;
  bool seen_row = false;  // a row other than a comment or blank
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();  // CRLF files
    const std::string where = name + ":" + std::to_string(line_number) + ": ";
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    // One header row naming the columns, as the first row ("stamp tx ty tz qx qy qz qw"): the
    // reference paper's loader skips rows that begin with "stamp" or "frame", so its files may have one.
    const bool first_row = !seen_row;
    seen_row = true;
    if (first_row && isColumnNames(line.substr(first))) continue;

    std::istringstream words(line);
    std::array<double, 8> v{};
    std::string word;
    int n = 0;
    while (words >> word) {
      if (n == 8) throw Error(where + "expected 8 numbers 't tx ty tz qx qy qz qw', found more");
      char* end = nullptr;
      v[n] = std::strtod(word.c_str(), &end);
      if (end == word.c_str() || *end != '\0') throw Error(where + "'" + word + "' is not a number");
      ++n;
    }
    if (n != 8) {
      throw Error(where + "expected 8 numbers 't tx ty tz qx qy qz qw', found " + std::to_string(n));
    }
    for (int i = 0; i < 8; ++i) {
      if (!std::isfinite(v[i])) throw Error(where + "non-finite value '" + std::to_string(v[i]) + "' (NaN or inf)");
    }
    Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);  // (w, x, y, z)
    const double norm = q.norm();
    if (std::abs(norm - 1.0) > kQuaternionNormTolerance) {
      std::ostringstream text;
      text << where << "quaternion (qx qy qz qw) has norm " << norm << ", must be 1 (within " << kQuaternionNormTolerance
           << ")";
      throw Error(text.str());
    }
    // Nanoseconds (ORB-SLAM3's EuRoC-style files: "1403636580838555648.000000 ..."), told by the first
    // pose: 1e11 s would be the year 5138.
    if (trajectory.poses_.empty()) nanoseconds = v[0] >= 1e11;
    if (nanoseconds) v[0] *= 1e-9;
    if (!trajectory.poses_.empty() && !(v[0] > trajectory.poses_.back().t_s)) {
      std::ostringstream text;
      text.precision(17);
      text << where << "timestamp " << v[0] << " is not after the previous one (" << trajectory.poses_.back().t_s << ")";
      throw Error(text.str());
    }
    StampedPose pose;
    pose.t_s = v[0];
    pose.T_world_cam.linear() = q.normalized().toRotationMatrix();
    pose.T_world_cam.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    trajectory.poses_.push_back(pose);
  }
  return trajectory;
}

std::optional<StampedPose> TumTrajectory::lookup(double t_s, double tolerance_s) const {
  if (poses_.empty() || !std::isfinite(t_s)) return std::nullopt;
  const auto after = std::lower_bound(poses_.begin(), poses_.end(), t_s,
                                      [](const StampedPose& p, double t) { return p.t_s < t; });
  auto best = poses_.end();
  if (after != poses_.end()) best = after;
  if (after != poses_.begin()) {
    const auto before = std::prev(after);
    if (best == poses_.end() || t_s - before->t_s <= best->t_s - t_s) best = before;
  }
  if (std::abs(best->t_s - t_s) > tolerance_s) return std::nullopt;
  return *best;
}

}  // namespace cenote::io
