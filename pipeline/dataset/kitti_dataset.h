// kitti_dataset.h: the KITTI odometry layout of one sequence.
//   <seq>/image_2, <seq>/image_3 (colour; else image_0, image_1 grey): 000000.png ...
//   <seq>/calib.txt   rectified projection matrices P0..P3
//   <seq>/times.txt   one timestamp per frame, seconds
//   ground truth <dataset>/poses/<seq>.txt (poses of camera 0), looked up beside the sequences
//   folder when present.
// Images are already rectified: the calibration passes through the rectifier. KITTI poses describe
// camera 0; the colour camera sits at -K^-1 P2(:, 3) in camera 0's frame, so T_body_cam says so.
// Threads: see stereo_dataset.h.
#pragma once

#include <vector>

#include "pipeline/dataset/stereo_dataset.h"

namespace cenote::pipeline {

class KittiDataset final : public StereoDataset {
 public:
  // @throws cenote::Error for missing folders or files, or a malformed calib.txt / times.txt.
  explicit KittiDataset(const std::string& sequence_dir);

  size_t size() const override { return times_.size(); }
  double timestamp(size_t index) const override { return times_.at(index); }
  std::string frameName(size_t index) const override;
  StereoFrame load(size_t index) const override;
  const StereoCalibration& calibration() const override { return calibration_; }
  Eigen::Isometry3d T_body_cam() const override { return T_body_cam_; }
  std::optional<TrajectorySource> defaultTrajectory() const override;
  // KITTI poses: timed by times.txt, of camera 0 (composed with T_body_cam); TUM: the left camera.
  TrajectorySource trajectoryFile(const std::string& path, io::TrajectoryFormat format) const override;
  std::string describe() const override;

 private:
  std::string dir_, left_dir_, right_dir_;
  std::vector<double> times_;
  StereoCalibration calibration_;
  Eigen::Isometry3d T_body_cam_ = Eigen::Isometry3d::Identity();
};

}  // namespace cenote::pipeline
