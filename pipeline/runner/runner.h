// runner.h: the real-time pipeline over a recorded sequence.
//
//   read + rectify ──► stereo ──► fusion ──► output (+ an optional sink, e.g. the map)
//
// Each stage runs on its own thread, connected by bounded queues (run.queue_depth frames), so a
// slow stage applies back-pressure and memory stays constant whatever the sequence length. Frames
// without a pose (no trajectory samples bracketing them within run.pose_max_gap_s), frames that
// are not keyframes (when keyframe thresholds are set) and frames whose images cannot be read are
// skipped and counted, never guessed. Setting `stop` (e.g. from a Ctrl-C handler) ends reading;
// the frames already read are finished and everything is written.
//
// Outputs in the output folder: points.ply (fused coloured points, world frame), and with
// run.write_depth, depth/<name>.depth.pfm, .conf.pfm and .jpg (the rectified left image) of every
// fused (or raw) frame, <name>
// being the dataset's own (StereoDataset::frameName: EuRoC nanoseconds, KITTI 000123), and
// depth/frames.csv with each map's time, rectified intrinsics and pose (depth_index.h; `cenote fuse
// --depth-dir OUT` reads it).
// Threads: run() blocks; it uses four threads plus OpenMP inside stereo and fusion.
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "common/point_batch.h"
#include "pipeline/dataset/stereo_dataset.h"
#include "pipeline/runner/run_config.h"
#include "common/stage_timer.h"
#include "io/trajectory/trajectory.h"

namespace cenote::pipeline {

struct RunReport {
  size_t frames_in = 0;             // frames in the dataset (up to run.max_frames); a recording's: the
                                    // pairs read (its expected count when interrupted)
  size_t frames_processed = 0;      // frames that went through stereo
  size_t frames_fused = 0;          // fused reference frames emitted (or raw frames without fusion)
  size_t skipped_out_of_order = 0;  // timestamps not after the previous frame's (frame_admission.h)
  size_t skipped_no_pose = 0;
  size_t skipped_not_keyframe = 0;
  size_t skipped_unreadable = 0;
  size_t points_written = 0;
  bool interrupted = false;
  // What the source counted (a recording: "unpaired_images", "out_of_order_images") and, for a
  // recording cut short, where it stopped (FrameCursor::truncation()); in report.json as "source".
  std::map<std::string, std::uint64_t> source_counts;
  std::string source_truncation;
  std::vector<std::string> source_skipped;  // the damage it stepped over (FrameCursor::skipped())
  // What the trajectory's poses were taken to describe ("camera" or "body"; empty: not set) and
  // whether that was assumed (CameraTrajectory::frame_assumed), with the hint printed for it.
  std::string pose_frame;
  bool pose_frame_assumed = false;
  std::string pose_frame_hint;
  // The pose source had keyframes only (CameraTrajectory::keyframes_only), `pose_keyframes` of them:
  // only the frames at a keyframe were processed, the others counted as without pose.
  bool keyframes_only = false;
  size_t pose_keyframes = 0;
  double wall_s = 0.0;
  double fps = 0.0;                            // frames processed per second of wall time
  double peak_memory_mb = 0.0;                 // resident set, high-water mark of the process
  std::map<std::string, StageSummary> stages;  // read_rectify, stereo, fusion, output (+ map: the sink)
  // CPU ms per frame processed (user + system, every thread; common/cpu_clock.h): of each stage
  // above, with its OpenMP threads; "other" (the rest of the process during the run: OpenCV's
  // and TBB's pools, the queues, the progress bar) and "total" (the whole process during the run).
  std::map<std::string, double> cpu_ms_per_frame;

  // JSON object with the keys above ("stages": {name: {median_ms, p95_ms, mean_ms, frames}},
  // "cpu_ms_per_frame": {name: ms}).
  std::string toJson() const;
  // A table for a person at a terminal.
  std::string toTable() const;
};

// Called on the output thread with every batch of fused points (world frame) and the pose of the
// rectified left camera that saw them (T_world_cam, FusedFrame's).
using PointSink = std::function<void(const PointBatch&, const Eigen::Isometry3d& T_world_cam)>;
// Called on the output thread after each frame: frames done (processed or skipped) of total.
using ProgressCallback = std::function<void(size_t done, size_t total)>;

class Runner {
 public:
  // @throws cenote::Error listing every invalid setting.
  explicit Runner(PipelineConfig config);

  // @param camera_trajectory poses of the dataset's left (raw) camera, T_world_cam.
  // @param out_dir created if absent.
  // @throws cenote::Error when an output cannot be written (what was written so far stays).
  RunReport run(const StereoDataset& dataset, const io::Trajectory& camera_trajectory, const std::string& out_dir,
                const std::atomic<bool>& stop, const PointSink& sink = {}, const ProgressCallback& progress = {});

  const PipelineConfig& config() const { return config_; }

 private:
  PipelineConfig config_;
};

// Which trajectory a run uses (the options of `cenote run`).
struct TrajectoryRequest {
  std::string path;    // empty: the dataset's own ground truth
  std::string format;  // "tum", "euroc", "kitti", "okvis", "openvins"; empty: detected from the file
  std::string times;   // times of a format without timestamps (KITTI); empty: the dataset's
                       // own (a KITTI sequence's times.txt)
  PoseFrame pose_frame = PoseFrame::kAuto;
};

// The trajectory of the dataset's raw left camera, and how it was made.
struct CameraTrajectory {
  io::Trajectory trajectory;         // T_world_cam of the raw left camera
  bool file_describes_body = false;  // the file's poses were composed with T_body_cam
  // true: pose_frame was auto, the format does not say which frame its poses describe (TUM; KITTI
  // outside a KITTI sequence) and the dataset's T_body_cam is not the identity, so the choice
  // (the camera) changes the map; `note` then says so and how to choose.
  bool frame_assumed = false;
  std::string note;  // one line for a person; empty when nothing was assumed
  // true: a pose source of keyframes only (isKeyframeTrajectory); the run then poses only the frames
  // with a pose of their own (`cenote run` sets run.pose_max_gap_s to 1 us) and its report says so.
  bool keyframes_only = false;
  const char* fileFrame() const { return file_describes_body ? "body" : "camera"; }
};

// True when `trajectory` holds keyframes only, as VIO systems write them (OKVIS / SVIn2 keyframe
// poses, ORB-SLAM3's KeyFrameTrajectory.txt): at least 2 poses, every pose at the timestamp of one of
// the dataset's frames (within 1 us), and fewer poses than 3/4 of the frames between its first and
// last pose. Interpolating between keyframes seconds apart would invent poses. The frame times are
// dataset.frameTimes(): a recording is read once for its pairs' header stamps (no image held or
// decoded), unless the pose count alone rules keyframes out. @throws Error from that reading.
bool isKeyframeTrajectory(const io::Trajectory& trajectory, const StereoDataset& dataset);
// The same test against frame times (seconds, any order): a recording's, read with its pose topic.
bool isKeyframeTrajectory(const io::Trajectory& trajectory, std::vector<double> frame_times);

// The trajectory of the dataset's left camera: `request.path` (read the way the dataset reads its
// own files, StereoDataset::trajectoryFile: a KITTI sequence times KITTI poses with its times.txt
// and applies its cam0-to-camera offset, exactly as for its default trajectory) or the dataset's
// own; body poses are composed with the dataset's T_body_cam.
// @throws cenote::Error when there is no trajectory at all, it cannot be read, KITTI poses have no
//         times, or `request.times` is given for a format that has its own timestamps.
CameraTrajectory loadCameraTrajectory(const StereoDataset& dataset, const TrajectoryRequest& request);

// loadCameraTrajectory(dataset, {trajectory_path, trajectory_format, "", pose_frame}).trajectory.
io::Trajectory cameraTrajectory(const StereoDataset& dataset, const std::string& trajectory_path,
                                const std::string& trajectory_format, PoseFrame pose_frame);

// Peak resident memory of this process in MiB (getrusage).
double peakMemoryMb();

}  // namespace cenote::pipeline
