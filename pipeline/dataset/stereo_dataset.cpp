#include "pipeline/dataset/stereo_dataset.h"

#include <filesystem>

#include "common/enum_names.h"
#include "common/error.h"
#include "pipeline/dataset/euroc_dataset.h"
#include "pipeline/dataset/kitti_dataset.h"

namespace cenote::pipeline {
namespace fs = std::filesystem;

DatasetFormat parseDatasetFormat(const std::string& name) {
  constexpr EnumName<DatasetFormat> kNames[] = {
      {DatasetFormat::kAuto, "auto"}, {DatasetFormat::kEuroc, "euroc"}, {DatasetFormat::kKitti, "kitti"}};
  return parseEnumName(kNames, name, "dataset format '" + name + "'");
}

TrajectorySource StereoDataset::trajectoryFile(const std::string& path, io::TrajectoryFormat format) const {
  TrajectorySource source;
  source.path = path;
  source.format = format;
  source.describes_body = format == io::TrajectoryFormat::kEuroc;
  source.frame_assumed = format != io::TrajectoryFormat::kEuroc;
  return source;
}

std::unique_ptr<StereoDataset> openDataset(const std::string& path, DatasetFormat format) {
  if (!fs::exists(path)) throw Error("dataset " + path + ": no such folder");
  if (format == DatasetFormat::kAuto) {
    if (fs::exists(fs::path(path) / "mav0" / "cam0" / "data.csv") || fs::exists(fs::path(path) / "cam0" / "data.csv")) {
      format = DatasetFormat::kEuroc;
    } else if (fs::exists(fs::path(path) / "times.txt") && fs::exists(fs::path(path) / "calib.txt")) {
      format = DatasetFormat::kKitti;
    } else {
      throw Error("dataset " + path +
                  ": unknown layout (expected EuRoC mav0/cam0/data.csv or a KITTI sequence with times.txt and calib.txt)");
    }
  }
  if (format == DatasetFormat::kEuroc) return std::make_unique<EurocDataset>(path);
  return std::make_unique<KittiDataset>(path);
}

}  // namespace cenote::pipeline
