#include "pipeline/runner/depth_index.h"

#include <cstdio>

#include "common/error.h"
#include "common/text_parse.h"

namespace cenote::pipeline {
namespace {

constexpr const char* kHeader = "name,t_s,fx,fy,cx,cy,r00,r01,r02,tx,r10,r11,r12,ty,r20,r21,r22,tz";
constexpr size_t kNumbers = 17;  // after the name

}  // namespace

DepthIndexWriter::DepthIndexWriter(const std::string& path) : path_(path), out_(path) {
  out_ << kHeader << "\n";
  if (!out_) throwWriteError(path_, "cannot create the file");
}

void DepthIndexWriter::add(const DepthIndexRow& row) {
  const Eigen::Matrix<double, 3, 4> T = row.T_world_cam.matrix().topRows<3>();
  const double numbers[kNumbers] = {row.t_s, row.K(0, 0), row.K(1, 1), row.K(0, 2), row.K(1, 2), T(0, 0),
                                    T(0, 1), T(0, 2),     T(0, 3),     T(1, 0),     T(1, 1),     T(1, 2),
                                    T(1, 3), T(2, 0),     T(2, 1),     T(2, 2),     T(2, 3)};
  out_ << row.name;
  char text[32];
  for (double v : numbers) {
    std::snprintf(text, sizeof(text), ",%.17g", v);
    out_ << text;
  }
  out_ << "\n";
  out_.flush();
  if (!out_) throwWriteError(path_, "write failed");
}

std::vector<DepthIndexRow> readDepthIndex(const std::string& path) {
  std::ifstream in(path);
  if (!in) throwReadError(path, "permission denied", "depth index ");
  std::vector<DepthIndexRow> rows;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (number == 1 && line == kHeader) continue;
    const std::string where = path + ":" + std::to_string(number);
    const size_t comma = line.find(',');
    std::vector<double> v;
    std::string bad;
    if (comma == std::string::npos || comma == 0 || !parseNumberList(line.substr(comma + 1), ',', v, &bad)) {
      throw Error(where + ": '" + bad + "' is not a number (expected " + kHeader + ")");
    }
    if (v.size() != kNumbers) {
      throw Error(where + ": " + std::to_string(v.size() + 1) + " fields, expected 18 (" + kHeader + ")");
    }
    DepthIndexRow row;
    row.name = line.substr(0, comma);
    row.t_s = v[0];
    row.K << v[1], 0.0, v[3], 0.0, v[2], v[4], 0.0, 0.0, 1.0;
    Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) T(r, c) = v[5 + 4 * r + c];
    row.T_world_cam.matrix() = T;
    rows.push_back(row);
  }
  return rows;
}

}  // namespace cenote::pipeline
