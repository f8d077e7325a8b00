#include "io/trajectory/vio_trajectory.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <sstream>

#include "common/error.h"

namespace cenote::io {
namespace {

std::string trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\r#");
  const size_t b = s.find_last_not_of(" \t\r");
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream in(line);
  std::string cell;
  while (std::getline(in, cell, ',')) out.push_back(trim(cell));
  return out;
}

// The columns read, in the order of the values they give, with their header names (a unit suffix such
// as "timestamp [ns]" or "p_WS_W_x [m]" is allowed).
constexpr std::array<const char*, 8> kColumns = {"timestamp", "p_WS_W_x", "p_WS_W_y", "p_WS_W_z",
                                                 "q_WS_x",    "q_WS_y",   "q_WS_z",   "q_WS_w"};

}  // namespace

Trajectory readOkvisCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error("cannot read trajectory " + path + ": no such file or not readable");
  std::array<size_t, 8> column = {0, 1, 2, 3, 4, 5, 6, 7};
  std::vector<StampedPose> poses;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const std::vector<std::string> cells = splitCsv(line);
    if (cells.empty() || (cells.size() == 1 && cells[0].empty())) continue;
    const std::string where = path + ":" + std::to_string(number) + ": ";
    if (std::isalpha(static_cast<unsigned char>(cells[0][0])) != 0) {  // the header
      for (size_t k = 0; k < kColumns.size(); ++k) {
        const auto found = std::find_if(cells.begin(), cells.end(), [&](const std::string& c) {
          return c == kColumns[k] || c.rfind(std::string(kColumns[k]) + " ", 0) == 0;
        });
        if (found == cells.end())
          throw Error(where + "the header has no column " + kColumns[k] +
                      " (OKVIS / SVIn2: timestamp, p_WS_W_x, p_WS_W_y, p_WS_W_z, q_WS_x, q_WS_y, q_WS_z, q_WS_w, ...)");
        column[k] = static_cast<size_t>(found - cells.begin());
      }
      continue;
    }
    std::array<double, 8> v{};
    for (size_t k = 0; k < v.size(); ++k) {
      if (column[k] >= cells.size())
        throw Error(where + "has " + std::to_string(cells.size()) + " values, no " + kColumns[k]);
      const std::string& cell = cells[column[k]];
      char* end = nullptr;
      v[k] = std::strtod(cell.c_str(), &end);
      if (cell.empty() || *end != '\0' || !std::isfinite(v[k]))
        throw Error(where + kColumns[k] + " '" + cell + "' is not a number");
    }
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (std::abs(q.norm() - 1.0) > kQuaternionNormTolerance)
      throw Error(where + "quaternion (q_WS_x q_WS_y q_WS_z q_WS_w) is not of unit norm");
    StampedPose pose;
    pose.t_s = v[0] * 1e-9;
    pose.T_world_cam.linear() = q.normalized().toRotationMatrix();
    pose.T_world_cam.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    poses.push_back(pose);
  }
  return Trajectory(std::move(poses), path);
}

}  // namespace cenote::io
