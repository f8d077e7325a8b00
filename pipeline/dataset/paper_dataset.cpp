#include "pipeline/dataset/paper_dataset.h"

#include <filesystem>
#include <fstream>

#include "common/error.h"

namespace cenote::pipeline {
namespace fs = std::filesystem;
namespace {

std::string trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\r");
  const size_t b = s.find_last_not_of(" \t\r");
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

// A timestamp of filename_mapping.csv: seconds, or integer nanoseconds when 1e11 or more.
bool parseStamp(const std::string& text, double& t_s) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(v) || v < 0) return false;
  const bool integer = text.find_first_not_of("0123456789") == std::string::npos;
  t_s = integer && v >= 1e11 ? static_cast<double>(std::stoll(text)) * 1e-9 : v;
  return true;
}

}  // namespace

bool PaperDataset::looksLike(const std::string& dir) {
  const fs::path root(dir);
  return fs::exists(root / "filename_mapping.csv") && fs::exists(root / "intrinsics.yaml") &&
         fs::is_directory(root / "left") && fs::is_directory(root / "right");
}

PaperDataset::PaperDataset(const std::string& root) : root_(root) {
  const fs::path dir(root);
  for (const char* sub : {"left", "right"})
    if (!fs::is_directory(dir / sub)) throw Error("paper dataset " + root + ": missing folder " + (dir / sub).string());
  const fs::path csv = dir / "filename_mapping.csv";
  std::ifstream in(csv);
  if (!in) throw Error("paper dataset: missing " + csv.string());
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    line = trim(line);
    if (line.empty() || line[0] == '#') continue;
    const std::string where = csv.string() + ":" + std::to_string(number) + ": ";
    const size_t comma = line.find(',');
    if (comma == std::string::npos) throw Error(where + "expected 'timestamp,filename'");
    const std::string stamp = trim(line.substr(0, comma));
    const std::string file = trim(line.substr(comma + 1));
    double t_s = 0.0;
    if (!parseStamp(stamp, t_s)) {
      if (frames_.empty() && unpaired_ == 0) continue;  // a header row
      throw Error(where + "'" + stamp + "' is not a timestamp (seconds, or integer nanoseconds)");
    }
    if (file.empty()) throw Error(where + "missing file name");
    if (!frames_.empty() && t_s <= frames_.back().t_s) throw Error(where + "timestamp is not after the previous one");
    const fs::path left = dir / "left" / file;
    const fs::path right = dir / "right" / file;
    if (!fs::exists(left) || !fs::exists(right)) {
      ++unpaired_;
      continue;
    }
    frames_.push_back({t_s, fs::path(file).stem().string(), left.string(), right.string()});
  }
  calibration_ = readPaperIntrinsics((dir / "intrinsics.yaml").string());
}

StereoFrame PaperDataset::load(size_t index) const {
  const Frame& f = frames_.at(index);
  return readStereoFrame(f.t_s, f.left, f.right);
}

std::optional<TrajectorySource> PaperDataset::defaultTrajectory() const {
  const fs::path poses = fs::path(root_) / "poses.txt";
  if (!fs::exists(poses)) return std::nullopt;
  return TrajectorySource{poses.string(), io::TrajectoryFormat::kTum, "", false, false};
}

std::optional<std::string> PaperDataset::referenceCloud() const {
  const fs::path cloud = fs::path(root_) / "colmap.ply";
  if (!fs::exists(cloud)) return std::nullopt;
  return cloud.string();
}

std::string PaperDataset::describe() const {
  return "paper layout " + root_ + ": " + std::to_string(frames_.size()) + " stereo frames" +
         (unpaired_ ? ", " + std::to_string(unpaired_) + " rows without both images left out" : "");
}

}  // namespace cenote::pipeline
