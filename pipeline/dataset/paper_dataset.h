// paper_dataset.h: the folder layout of the reference paper's datasets (Wang, Joshi et al., ICRA 2023).
//   <root>/left/, <root>/right/   PNG images, the same file name in both for one stereo frame
//   <root>/filename_mapping.csv   rows "ts,ts.png": the frame's timestamp and its file name (a header row
//                                 is skipped); seconds, or integer nanoseconds (a value of 1e11 or more)
//   <root>/poses.txt              TUM rows "ts tx ty tz qx qy qz qw": poses of the left camera, the default
//                                 trajectory
//   <root>/intrinsics.yaml        OpenCV FileStorage: K and D per camera, image size, baseline in
//                                 millimetres, stereo R and T (readPaperIntrinsics)
//   <root>/colmap.ply             optional: COLMAP's reconstruction, the reference cloud of `cenote eval`
// Frames are the rows whose image exists in both folders; a row missing either image is counted in
// unpairedFrames() and left out. The poses describe the left camera: T_body_cam is the identity.
// Threads: see stereo_dataset.h.
#pragma once

#include <vector>

#include "pipeline/dataset/stereo_dataset.h"

namespace cenote::pipeline {

class PaperDataset final : public StereoDataset {
 public:
  // @throws cenote::Error for a missing file or folder, a malformed filename_mapping.csv line (file and
  //         line named), timestamps that do not increase, or an invalid intrinsics.yaml.
  explicit PaperDataset(const std::string& root);

  size_t size() const override { return frames_.size(); }
  double timestamp(size_t index) const override { return frames_.at(index).t_s; }
  std::string frameName(size_t index) const override { return frames_.at(index).name; }
  StereoFrame load(size_t index) const override;
  const StereoCalibration& calibration() const override { return calibration_; }
  Eigen::Isometry3d T_body_cam() const override { return Eigen::Isometry3d::Identity(); }
  std::optional<TrajectorySource> defaultTrajectory() const override;
  std::optional<std::string> referenceCloud() const override;
  std::string describe() const override;

  size_t unpairedFrames() const { return unpaired_; }

  // True when `dir` holds the layout's files (filename_mapping.csv, intrinsics.yaml, left/, right/).
  static bool looksLike(const std::string& dir);

 private:
  struct Frame {
    double t_s;
    std::string name;  // the file name without its extension
    std::string left, right;
  };
  std::string root_;
  std::vector<Frame> frames_;
  StereoCalibration calibration_;
  size_t unpaired_ = 0;
};

}  // namespace cenote::pipeline
