#include "pipeline/dataset/euroc_dataset.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>

#include "common/error.h"

namespace cenote::pipeline {
namespace fs = std::filesystem;
namespace {

struct CsvImage {
  int64_t t_ns;
  std::string file;
};

std::string trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\r");
  const size_t b = s.find_last_not_of(" \t\r");
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

// cam*/data.csv: "#timestamp [ns],filename".
std::vector<CsvImage> readImageList(const fs::path& camera_dir) {
  const fs::path csv = camera_dir / "data.csv";
  std::ifstream in(csv);
  if (!in) throw Error("EuRoC: missing " + csv.string());
  std::vector<CsvImage> images;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    line = trim(line);
    if (line.empty() || line[0] == '#') continue;
    const size_t comma = line.find(',');
    const std::string where = csv.string() + ":" + std::to_string(number) + ": ";
    if (comma == std::string::npos) throw Error(where + "expected 'timestamp_ns,filename'");
    const std::string stamp = trim(line.substr(0, comma));
    char* end = nullptr;
    const long long t = std::strtoll(stamp.c_str(), &end, 10);
    if (stamp.empty() || *end != '\0' || t < 0) throw Error(where + "'" + stamp + "' is not a timestamp in nanoseconds");
    const std::string file = trim(line.substr(comma + 1));
    if (file.empty()) throw Error(where + "missing file name");
    if (!images.empty() && t <= images.back().t_ns) throw Error(where + "timestamp is not after the previous one");
    images.push_back({t, (camera_dir / "data" / file).string()});
  }
  return images;
}

}  // namespace

EurocDataset::EurocDataset(const std::string& root) {
  fs::path mav0 = fs::path(root) / "mav0";
  if (!fs::exists(mav0)) mav0 = fs::path(root);
  mav0_ = mav0.string();
  const std::vector<CsvImage> left = readImageList(mav0 / "cam0");
  const std::vector<CsvImage> right = readImageList(mav0 / "cam1");
  // Pair by timestamp; both lists are sorted.
  size_t j = 0;
  for (const CsvImage& l : left) {
    while (j < right.size() && right[j].t_ns < l.t_ns) {
      ++j;
      ++unpaired_;
    }
    if (j < right.size() && right[j].t_ns == l.t_ns) {
      frames_.push_back({l.t_ns, static_cast<double>(l.t_ns) * 1e-9, l.file, right[j].file});
      ++j;
    } else {
      ++unpaired_;
    }
  }
  unpaired_ += right.size() - j;
  calibration_ = readEurocSensorPair((mav0 / "cam0" / "sensor.yaml").string(), (mav0 / "cam1" / "sensor.yaml").string());
  T_body_cam_ = readEurocBodyCamera((mav0 / "cam0" / "sensor.yaml").string());
}

StereoFrame EurocDataset::load(size_t index) const {
  const Frame& f = frames_.at(index);
  return readStereoFrame(f.t_s, f.left, f.right);
}

std::optional<TrajectorySource> EurocDataset::defaultTrajectory() const {
  const fs::path gt = fs::path(mav0_) / "state_groundtruth_estimate0" / "data.csv";
  if (!fs::exists(gt)) return std::nullopt;
  return TrajectorySource{gt.string(), io::TrajectoryFormat::kEuroc, "", true};
}

std::string EurocDataset::describe() const {
  return "EuRoC " + mav0_ + ": " + std::to_string(frames_.size()) + " stereo frames" +
         (unpaired_ ? ", " + std::to_string(unpaired_) + " unpaired images left out" : "");
}

}  // namespace cenote::pipeline
