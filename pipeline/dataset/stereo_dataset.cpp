#include "pipeline/dataset/stereo_dataset.h"

#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "common/enum_names.h"
#include "common/error.h"
#include "io/image/image_io.h"
#include "pipeline/dataset/euroc_dataset.h"
#include "pipeline/dataset/kitti_dataset.h"
#include "pipeline/dataset/paper_dataset.h"

namespace cenote::pipeline {
namespace fs = std::filesystem;

DatasetFormat parseDatasetFormat(const std::string& name) {
  constexpr EnumName<DatasetFormat> kNames[] = {{DatasetFormat::kAuto, "auto"},
                                                {DatasetFormat::kEuroc, "euroc"},
                                                {DatasetFormat::kKitti, "kitti"},
                                                {DatasetFormat::kPaper, "paper"},
                                                {DatasetFormat::kRecording, "bag"}};
  return parseEnumName(kNames, name, "dataset format '" + name + "'");
}

StereoFrame readStereoFrame(double t_s, const std::string& left_path, const std::string& right_path) {
  StereoFrame frame;
  frame.t_s = t_s;
  frame.left = io::readImage(left_path, cv::IMREAD_UNCHANGED);
  frame.right = io::readImage(right_path, cv::IMREAD_UNCHANGED);
  return frame;
}

Eigen::Isometry3d readEurocBodyCamera(const std::string& sensor_yaml) {
  const cv::Matx44d T = readEurocBodyFromSensor(sensor_yaml);
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out.linear()(r, c) = T(r, c);
    out.translation()(r) = T(r, 3);
  }
  return out;
}

TrajectorySource StereoDataset::trajectoryFile(const std::string& path, io::TrajectoryFormat format) const {
  TrajectorySource source;
  source.path = path;
  source.format = format;
  source.describes_body = io::describesBody(format);
  source.frame_assumed = !io::describesBody(format);
  return source;
}

namespace {

class IndexCursor final : public FrameCursor {
 public:
  explicit IndexCursor(const StereoDataset& dataset) : dataset_(dataset) {}
  bool next() override { return ++index_ < dataset_.size(); }
  double timestamp() const override { return dataset_.timestamp(index_); }
  std::string frameName() const override { return dataset_.frameName(index_); }
  StereoFrame load() override { return dataset_.load(index_); }

 private:
  const StereoDataset& dataset_;
  size_t index_ = static_cast<size_t>(-1);
};

}  // namespace

std::unique_ptr<FrameCursor> StereoDataset::frames() const { return std::make_unique<IndexCursor>(*this); }

std::vector<double> StereoDataset::frameTimes() const {
  std::vector<double> times(size());
  for (size_t i = 0; i < times.size(); ++i) times[i] = timestamp(i);
  return times;
}

std::unique_ptr<StereoDataset> openDataset(const std::string& path, DatasetFormat format) {
  if (!fs::exists(path)) throw Error("dataset " + path + ": no such folder");
  if (format == DatasetFormat::kAuto) {
    if (fs::exists(fs::path(path) / "mav0" / "cam0" / "data.csv") || fs::exists(fs::path(path) / "cam0" / "data.csv")) {
      format = DatasetFormat::kEuroc;
    } else if (fs::exists(fs::path(path) / "times.txt") && fs::exists(fs::path(path) / "calib.txt")) {
      format = DatasetFormat::kKitti;
    } else if (PaperDataset::looksLike(path)) {
      format = DatasetFormat::kPaper;
    } else {
      throw Error("dataset " + path +
                  ": unknown layout (expected EuRoC mav0/cam0/data.csv, a KITTI sequence with times.txt and calib.txt, "
                  "or the paper's left/, right/, filename_mapping.csv and intrinsics.yaml)");
    }
  }
  if (format == DatasetFormat::kRecording) {
    throw Error("dataset " + path + ": a recording is opened with its topics (openRecordingDataset)");
  }
  if (format == DatasetFormat::kEuroc) return std::make_unique<EurocDataset>(path);
  if (format == DatasetFormat::kPaper) return std::make_unique<PaperDataset>(path);
  return std::make_unique<KittiDataset>(path);
}

}  // namespace cenote::pipeline
