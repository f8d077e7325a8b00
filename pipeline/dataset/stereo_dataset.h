// stereo_dataset.h: a recorded stereo sequence on disk, read frame by frame.
//   EuRoC / ASL layout (SVIn2, OKVIS, Kimera, OpenVINS users): euroc_dataset.h
//   KITTI odometry layout: kitti_dataset.h
//   the reference paper's layout (left/, right/, poses.txt, intrinsics.yaml): paper_dataset.h
//   ROS 1 bag, MCAP, ROS 2 bag (read front to back only): recording_dataset.h
// A dataset knows its frames' timestamps, its calibration, where its left camera sits in the frame
// that its default trajectory describes (T_traj_cam), and which trajectory file that is.
// Units: seconds, metres. Threads: load() is const and may run on any one thread at a time per
// dataset object (it only reads files).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pipeline/calibration/stereo_calibration.h"
#include "pipeline/frame/frames.h"
#include "io/trajectory/trajectory.h"

namespace cenote::pipeline {

// A trajectory file a dataset ships with, and what it describes.
struct TrajectorySource {
  std::string path;
  io::TrajectoryFormat format = io::TrajectoryFormat::kTum;
  std::string kitti_times;      // KITTI only
  bool describes_body = false;  // true: poses of the body (IMU); false: of the left camera
  // true: the format does not say which frame its poses describe (TUM; KITTI poses outside a KITTI
  // sequence), so describes_body is the format's habit (the camera), not a fact of the file.
  bool frame_assumed = false;
};

// The frames of a dataset front to back, in one pass: how `cenote run` reads them. A recording (a
// ROS bag) is read only this way; folders also by index.
class FrameCursor {
 public:
  virtual ~FrameCursor() = default;
  // Moves to the next frame; false after the last. @throws cenote::Error for damage it cannot step over.
  virtual bool next() = 0;
  virtual double timestamp() const = 0;
  virtual std::string frameName() const = 0;
  // The current frame's images, read or decoded only now. @throws cenote::Error when unreadable.
  virtual StereoFrame load() = 0;
  // What the source counted on the way ("unpaired_images": ...), for the run report.
  virtual std::map<std::string, std::uint64_t> counts() const { return {}; }
  // Where reading stopped short (a recording cut short), empty otherwise.
  virtual std::string truncation() const { return ""; }
  // The damage the source stepped over (a recording's corrupt chunks), one line each.
  virtual std::vector<std::string> skipped() const { return {}; }
};

class StereoDataset {
 public:
  virtual ~StereoDataset() = default;

  virtual size_t size() const = 0;
  virtual double timestamp(size_t index) const = 0;
  // The frame's name as recorded (EuRoC: its timestamp in nanoseconds; KITTI: "000123"), for
  // output files that line up with the dataset's own.
  virtual std::string frameName(size_t index) const = 0;
  // Reads frame `index` (raw images, as recorded).
  // @throws cenote::Error naming the file when an image is missing or unreadable.
  virtual StereoFrame load(size_t index) const = 0;
  virtual const StereoCalibration& calibration() const = 0;
  // Left camera in the body frame (EuRoC: cam0's T_BS; KITTI: the left camera relative to cam0,
  // the frame of KITTI's poses).
  virtual Eigen::Isometry3d T_body_cam() const = 0;
  // The ground-truth / reference trajectory found inside the dataset, if any.
  virtual std::optional<TrajectorySource> defaultTrajectory() const = 0;
  // How this dataset reads a trajectory file of `format` that the user names (`cenote run
  // --trajectory`): the times of a format without timestamps (KITTI: the sequence's times.txt) and
  // which frame its poses describe (EuRoC CSV: the body; KITTI poses on a KITTI sequence: camera 0,
  // the frame T_body_cam starts from; TUM: the camera, assumed). The dataset's own file named by
  // its path gives the same source as defaultTrajectory().
  virtual TrajectorySource trajectoryFile(const std::string& path, io::TrajectoryFormat format) const;
  // The reference point cloud the dataset ships with (the paper's layout: colmap.ply), if any.
  virtual std::optional<std::string> referenceCloud() const { return std::nullopt; }
  virtual std::string describe() const = 0;
  // The frames front to back (the default walks index 0 .. size() - 1).
  virtual std::unique_ptr<FrameCursor> frames() const;
  // The timestamps of the frames frames() gives, in its order, without loading an image (the default
  // asks timestamp(i); a recording reads its image topics' header stamps in a pass of their own).
  // @throws cenote::Error for what reading the frames throws.
  virtual std::vector<double> frameTimes() const;
};

enum class DatasetFormat { kAuto, kEuroc, kKitti, kPaper, kRecording };

// "auto", "euroc", "kitti", "paper" or "bag". @throws cenote::Error otherwise.
DatasetFormat parseDatasetFormat(const std::string& name);

// The raw frame at `t_s` from its two image files, read unchanged (8 or 16 bit, as recorded).
// @throws cenote::Error naming the file when an image is missing or unreadable.
StereoFrame readStereoFrame(double t_s, const std::string& left_path, const std::string& right_path);

// T_body_cam of an EuRoC sensor.yaml (its T_BS). @throws cenote::Error as readEurocBodyFromSensor.
Eigen::Isometry3d readEurocBodyCamera(const std::string& sensor_yaml);

// Opens a folder; kAuto recognises EuRoC by mav0/cam0/data.csv, KITTI by times.txt + calib.txt and the
// paper's layout by filename_mapping.csv + intrinsics.yaml + left/ + right/.
// (A recording is opened with its topics: openRecordingDataset, recording_dataset.h.)
// @throws cenote::Error naming the path and what was expected when it is neither.
std::unique_ptr<StereoDataset> openDataset(const std::string& path, DatasetFormat format = DatasetFormat::kAuto);

}  // namespace cenote::pipeline
