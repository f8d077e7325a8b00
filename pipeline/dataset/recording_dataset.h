// recording_dataset.h: a robot's recording (a ROS 1 bag; any io::Recording) as a stereo dataset,
// read front to back in one pass.
//   Images: two topics of sensor_msgs/Image or sensor_msgs/CompressedImage, named or taken from a
//     rig preset (RecordingConfig::rigs), paired by header stamp (stamp_pairing.h); unpaired images
//     are counted. Only admitted frames are decoded (FrameCursor::load()).
//   Calibration: a file (readCalibrationFile: OpenCV YAML, EuRoC cam0/sensor.yaml, KITTI calib.txt)
//     or the two cameras' sensor_msgs/CameraInfo (<camera namespace>/camera_info beside each image
//     topic): K, D, R, P as ROS's stereo calibration publishes them; the baseline from the right
//     camera's P[3] = -fx' * B.
//   Poses: a pose topic (readPoseTopic: nav_msgs/Odometry, geometry_msgs/PoseStamped,
//     geometry_msgs/TransformStamped, or one parent/child pair of tf2_msgs/TFMessage), read in a pass
//     of its own (poses only: no image is decoded), or a trajectory file as for any dataset.
// Memory: one chunk of the recording and at most RecordingConfig::sync_queue images.
// Units: seconds (stamps in nanoseconds converted as EuRoC's are: ns * 1e-9), metres.
// Threads: the dataset is immutable after construction; each frames() cursor opens the file anew
// and is used by one thread.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "io/bag/recording.h"
#include "io/bag/ros_messages.h"
#include "io/trajectory/trajectory.h"
#include "pipeline/dataset/recording_config.h"
#include "pipeline/dataset/stereo_dataset.h"

namespace cenote::pipeline {

struct RecordingTopics {
  std::string left, right;            // image topics; both empty: the preset RecordingConfig::rig names
  std::string calibration;            // a calibration file; empty: the CameraInfo topics
  std::string left_info, right_info;  // empty: <namespace of the image topic>/camera_info
};

class RecordingDataset final : public StereoDataset {
 public:
  // Opens the recording, checks the topics, reads the calibration and decodes the first pair to
  // check that its images have the calibrated size.
  // @throws Error naming the recording and the topic: a topic not in the recording (with the
  //         image topics it has), of a type that is not an image, no preset topics found, no
  //         CameraInfo, a CameraInfo without a stereo baseline or that disagrees with the images;
  //         NotFoundError / IoError from the recording.
  RecordingDataset(const std::string& path, const RecordingTopics& topics, const RecordingConfig& config);

  // The pairs expected: the smaller of the two topics' message counts (pairs are known once read).
  size_t size() const override { return expected_; }
  // A recording is read front to back (frames()); by index: FailedPreconditionError.
  double timestamp(size_t index) const override;
  std::string frameName(size_t index) const override;
  StereoFrame load(size_t index) const override;
  const StereoCalibration& calibration() const override { return calibration_; }
  // From an EuRoC cam0/sensor.yaml calibration file (T_BS); otherwise the identity.
  Eigen::Isometry3d T_body_cam() const override { return T_body_cam_; }
  std::optional<TrajectorySource> defaultTrajectory() const override { return std::nullopt; }
  std::string describe() const override;
  std::unique_ptr<FrameCursor> frames() const override;
  // The stamps of the pairs frames() gives, from one pass that reads the images' header stamps and
  // pairs them as frames() does, holding no image. @throws as frames()'s next().
  std::vector<double> frameTimes() const override;

  const std::string& leftTopic() const { return left_; }
  const std::string& rightTopic() const { return right_; }

 private:
  std::string path_, left_, right_, calibration_source_;
  std::string compression_;  // io::Recording::compression(), for describe()
  RecordingConfig config_;
  size_t expected_ = 0;
  StereoCalibration calibration_;
  Eigen::Isometry3d T_body_cam_ = Eigen::Isometry3d::Identity();
};

// The poses of `topic` in `path` (nav_msgs/Odometry, geometry_msgs/PoseStamped,
// geometry_msgs/TransformStamped, tf2_msgs/TFMessage), by header stamp; for a TFMessage the
// transforms from `parent` to `child` (required then; leading '/' ignored).
// In the same pass, when `image_times` is given, the header stamps (seconds) of `image_topic`'s messages,
// the frames the poses are to cover (for isKeyframeTrajectory: a VIO's keyframe odometry).
// @throws Error naming the topic when it is missing, not a pose type, has no poses (of that pair),
//         or its stamps do not increase.
io::Trajectory readPoseTopic(const std::string& path, const std::string& topic, const std::string& parent = "",
                             const std::string& child = "", const std::string& image_topic = "",
                             std::vector<double>* image_times = nullptr);

// A stereo calibration from the CameraInfo of both cameras (K, D, R, P of each; ROS's convention:
// R rotates the raw camera into the rectified one, the right P[3] = -fx' * B).
// @throws Error naming the topics for sizes that differ, a distortion model other than plumb_bob /
//         rational_polynomial (or none), or a right P[3] of 0 (no baseline).
StereoCalibration calibrationFromCameraInfo(const io::RosCameraInfo& left, const io::RosCameraInfo& right,
                                            const std::string& left_topic, const std::string& right_topic);

}  // namespace cenote::pipeline
