// euroc_dataset.h: the EuRoC / ASL dataset layout.
//   <root>/mav0/cam0/data.csv      "#timestamp [ns],filename" rows; images in cam0/data/
//   <root>/mav0/cam0/sensor.yaml   intrinsics, radial-tangential distortion, T_BS (camera to body)
//   <root>/mav0/cam1/...           the right camera, same timestamps
//   <root>/mav0/state_groundtruth_estimate0/data.csv   body poses (optional), the default trajectory
// Frames are the timestamps present for both cameras; a timestamp in only one camera's list is
// counted in unpairedFrames() and left out.
// Threads: see stereo_dataset.h.
#pragma once

#include <vector>

#include "pipeline/dataset/stereo_dataset.h"

namespace cenote::pipeline {

class EurocDataset final : public StereoDataset {
 public:
  // @param root the folder holding mav0/ (or mav0 itself).
  // @throws cenote::Error for a missing file, a malformed data.csv line (file and line named) or an
  //         invalid calibration.
  explicit EurocDataset(const std::string& root);

  size_t size() const override { return frames_.size(); }
  double timestamp(size_t index) const override { return frames_.at(index).t_s; }
  std::string frameName(size_t index) const override { return std::to_string(frames_.at(index).t_ns); }
  StereoFrame load(size_t index) const override;
  const StereoCalibration& calibration() const override { return calibration_; }
  Eigen::Isometry3d T_body_cam() const override { return T_body_cam_; }
  std::optional<TrajectorySource> defaultTrajectory() const override;
  std::string describe() const override;

  size_t unpairedFrames() const { return unpaired_; }

 private:
  struct Frame {
    int64_t t_ns;
    double t_s;
    std::string left, right;
  };
  std::string mav0_;
  std::vector<Frame> frames_;
  StereoCalibration calibration_;
  Eigen::Isometry3d T_body_cam_ = Eigen::Isometry3d::Identity();
  size_t unpaired_ = 0;
};

}  // namespace cenote::pipeline
