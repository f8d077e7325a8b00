// `cenote run`: a recorded stereo sequence with poses in; fused points, depth maps and a timing
// report out, at camera rate. With --map, the fused points are integrated into an occupancy map;
// with --corrections DIR or SVIn2 FILE too (pipeline/runner/correction_events.h), the map keeps its frames in a
// frame store (mapping/history/map_history.h) and each loop-closure correction is applied when
// the run's fused frames pass its time (the rest at the end of the run).
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include "apps/cenote/commands.h"
#include "apps/cenote/dataset_source.h"
#include "apps/cenote/progress_bar.h"
#include "common/error.h"
#include "pipeline/dataset/recording_dataset.h"
#include "pipeline/dataset/stereo_dataset.h"
#include "common/yaml_section.h"
#include "eval/report/html_report.h"
#include "mapping/history/map_history.h"
#include "mapping/io/map_io.h"
#include "mapping/occupancy_map.h"
#include "pipeline/runner/correction_events.h"
#include "pipeline/runner/runner.h"

namespace cenote::apps {
namespace {

std::atomic<bool> g_stop{false};

extern "C" void onInterrupt(int) { g_stop = true; }

struct RunOptions {
  std::string dataset, format = "auto", trajectory, trajectory_format, trajectory_times, pose_frame, config, out, map,
                       corrections;
  std::string left, right, calibration, pose_topic, tf_parent, tf_child;  // recordings
  int fusion_views = 0, max_frames = -1;
  bool write_depth = false, report = false;
  double voxel_m = -1.0, keyframe_translation_m = -1.0, keyframe_rotation_deg = -1.0;
};

pipeline::PipelineConfig makeConfig(const RunOptions& o) {
  pipeline::PipelineConfig config;
  if (!o.config.empty()) config = pipeline::PipelineConfig::load(o.config);
  if (o.fusion_views == 1) {
    config.run.fuse = false;
  } else if (o.fusion_views > 1) {
    config.run.fuse = true;
    config.fusion.num_views = o.fusion_views;
  }
  if (o.max_frames >= 0) config.run.max_frames = o.max_frames;
  if (o.write_depth || o.report) config.run.write_depth = true;  // the report shows sample frames
  if (o.voxel_m >= 0.0) config.run.points_voxel_m = o.voxel_m;
  if (o.keyframe_translation_m >= 0.0) config.run.keyframe_translation_m = o.keyframe_translation_m;
  if (o.keyframe_rotation_deg >= 0.0) config.run.keyframe_rotation_deg = o.keyframe_rotation_deg;
  if (!o.pose_frame.empty()) config.run.pose_frame = pipeline::parsePoseFrame(o.pose_frame);
  return config;
}

// The `map:` section of the configuration file (defaults without one).
mapping::MapConfig mapConfig(const RunOptions& o) {
  mapping::MapConfig config;
  if (!o.config.empty()) readConfigFile(o.config, "map", config);
  return config;
}

// The dataset of the run, as `cenote stereo` opens one (dataset_source.h).
DatasetSource datasetSource(const RunOptions& o) {
  return {o.dataset,
          o.format,
          o.left,
          o.right,
          o.calibration,
          o.config,
          {{"--left", o.left}, {"--right", o.right}, {"--calibration", o.calibration}, {"--pose-topic", o.pose_topic}}};
}

bool isRecording(const RunOptions& o) { return apps::isRecording(datasetSource(o)); }

// The poses of a recording's pose topic, as the raw left camera's (composed with T_body_cam when
// they are body poses).
pipeline::CameraTrajectory poseTopicTrajectory(const pipeline::StereoDataset& dataset, const RunOptions& o,
                                               pipeline::PoseFrame pose_frame) {
  pipeline::CameraTrajectory out;
  // The left images' stamps come in the same pass: a VIO's keyframe odometry poses only some of them.
  const auto* recording = dynamic_cast<const pipeline::RecordingDataset*>(&dataset);
  std::vector<double> frame_times;
  const io::Trajectory poses = pipeline::readPoseTopic(o.dataset, o.pose_topic, o.tf_parent, o.tf_child,
                                                       recording ? recording->leftTopic() : "", &frame_times);
  out.file_describes_body = pose_frame == pipeline::PoseFrame::kBody;
  const bool extrinsics_matter = !dataset.T_body_cam().isApprox(Eigen::Isometry3d::Identity(), 1e-12);
  out.frame_assumed = pose_frame == pipeline::PoseFrame::kAuto && extrinsics_matter;
  if (out.frame_assumed) {
    out.note = "poses of " + o.pose_topic + " taken as camera poses (a pose topic does not say); pass --pose-frame body " +
               "if they are body (IMU) poses";
  }
  out.trajectory = out.file_describes_body ? poses.transformedBy(dataset.T_body_cam()) : poses;
  out.keyframes_only = pipeline::isKeyframeTrajectory(poses, std::move(frame_times));
  return out;
}

// The corrections of a run: each event's poses go to the map history when the run reaches them.
struct CorrectionReplay {
  std::vector<pipeline::CorrectionEvent> events;
  size_t next = 0;
  mapping::CorrectionSummary total;
  double ms = 0.0;

  void apply(mapping::MapHistory& history, const pipeline::CorrectionEvent& event) {
    std::vector<mapping::CorrectedPose> poses;
    poses.reserve(event.poses.size());
    for (const io::StampedPose& p : event.poses.poses()) poses.push_back({p.t_s, p.T_world_cam});
    const auto t0 = std::chrono::steady_clock::now();
    const mapping::CorrectionSummary s = history.correct(poses);
    ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    total.frames_moved += s.frames_moved;
    total.frames_replayed += s.frames_replayed;
    total.blocks_rebuilt += s.blocks_rebuilt;
    total.blocks_kept += s.blocks_kept;
  }
  // Applies the events known before t_s.
  void applyUntil(mapping::MapHistory& history, double t_s) {
    while (next < events.size() && events[next].t_s < t_s) apply(history, events[next++]);
  }
};

void run(const RunOptions& o) {
  pipeline::PipelineConfig config = makeConfig(o);
  if (!o.corrections.empty() && o.map.empty()) throw Error("--corrections " + o.corrections + " needs --map");
  const std::unique_ptr<pipeline::StereoDataset> dataset = openDatasetSource(datasetSource(o));
  if (!o.pose_topic.empty() && !o.trajectory.empty()) throw Error("give --pose-topic or --trajectory, not both");
  if (isRecording(o) && o.pose_topic.empty() && o.trajectory.empty()) {
    throw Error("no poses for recording " + o.dataset + ": give --pose-topic TOPIC (`cenote bag info " + o.dataset +
                "` lists its topics) or --trajectory FILE");
  }
  const pipeline::CameraTrajectory camera = o.pose_topic.empty()
                                                ? pipeline::loadCameraTrajectory(
                                                      *dataset, {o.trajectory, o.trajectory_format, o.trajectory_times,
                                                                 config.run.pose_frame})
                                                : poseTopicTrajectory(*dataset, o, config.run.pose_frame);
  // Keyframe poses seconds apart are no trajectory to interpolate: only the frames at a keyframe get a
  // pose (a gap of 1 us, Trajectory::poseAt's tolerance of the same time, interpolates nothing).
  if (camera.keyframes_only) config.run.pose_max_gap_s = 1e-6;
  pipeline::Runner runner(config);
  const io::Trajectory& trajectory = camera.trajectory;
  std::cerr << dataset->describe() << "; trajectory " << trajectory.name() << " (" << trajectory.size() << " poses, "
            << camera.fileFrame() << " poses" << (camera.frame_assumed ? ", assumed" : "") << ")\n";
  if (camera.frame_assumed) std::cerr << "note: " << camera.note << "\n";
  if (camera.keyframes_only)
    std::cerr << "note: the poses are keyframes only (" << trajectory.size()
              << "): only the frames at a keyframe are processed\n";
  // The map stage: every fused batch is integrated (free space along each ray, a hit at its end).
  std::unique_ptr<mapping::OccupancyMap> map;
  std::unique_ptr<mapping::MapHistory> history;
  CorrectionReplay replay;
  double last_batch_t_s = 0.0;
  pipeline::PointSink sink;
  if (!o.map.empty()) {
    mapping::mapFormatOf(o.map);  // an unknown extension fails now, not after the run
    map = std::make_unique<mapping::OccupancyMap>(mapConfig(o));
    sink = [&map](const PointBatch& batch, const Eigen::Isometry3d&) {
      if (!batch.empty()) map->integrate(batch);
    };
  }
  if (!o.corrections.empty()) {
    replay.events = pipeline::readCorrectionEvents(o.corrections, camera.file_describes_body, dataset->T_body_cam());
    history = std::make_unique<mapping::MapHistory>(*map);
    const double max_gap_s = runner.config().run.pose_max_gap_s;
    sink = [&, max_gap_s](const PointBatch& batch, const Eigen::Isometry3d& T_world_cam) {
      if (batch.empty()) return;
      last_batch_t_s = batch.t_s;
      replay.applyUntil(*history, batch.t_s);
      // The corrections give poses of the raw camera (as the trajectory): T_raw_cam is the
      // rectification's rotation, the same for every frame.
      const std::optional<Eigen::Isometry3d> T_world_raw = trajectory.poseAt(batch.t_s, max_gap_s);
      if (!T_world_raw) throw Error("run: no pose at t = " + std::to_string(batch.t_s) + " s for a fused frame");
      history->integrate(batch, T_world_cam, T_world_raw->inverse() * T_world_cam);
    };
  }

  g_stop = false;
  std::signal(SIGINT, onInterrupt);
  std::signal(SIGTERM, onInterrupt);
  ProgressBar bar("cenote run");
  pipeline::RunReport report = runner.run(*dataset, trajectory, o.out, g_stop, sink,
                                          [&bar](size_t done, size_t total) { bar.update(done, total); });
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);

  if (history) {
    // The events the run reached: up to its last frame.
    // A recording is read front to back and has no timestamp by index: its last fused frame's time.
    const double end_s = isRecording(o)        ? last_batch_t_s
                         : dataset->size() > 0 ? dataset->timestamp(std::min(dataset->size(), report.frames_in) - 1)
                                               : 0.0;
    replay.applyUntil(*history, std::nextafter(end_s, HUGE_VAL));
    std::printf("corrections: %zu of %zu events applied: %zu frames moved, %zu replayed, %zu blocks rebuilt, %zu kept "
                "(frames dropped from the store), %.1f ms; frame store %zu frames, %.1f MB\n",
                replay.next, replay.events.size(), replay.total.frames_moved, replay.total.frames_replayed,
                replay.total.blocks_rebuilt, replay.total.blocks_kept, replay.ms, history->numFrames(),
                history->storeBytes() / 1048576.0);
  }

  report.pose_frame = camera.fileFrame();
  report.pose_frame_assumed = camera.frame_assumed;
  report.pose_frame_hint = camera.note;
  report.keyframes_only = camera.keyframes_only;
  report.pose_keyframes = camera.keyframes_only ? trajectory.size() : 0;
  const std::string report_path = (std::filesystem::path(o.out) / "report.json").string();
  std::ofstream(report_path) << report.toJson();
  std::cout << report.toTable();
  std::cout << "outputs: " << o.out << "/" << pipeline::pointsFileName(runner.config().run) << ", " << report_path;
  if (runner.config().run.write_depth) std::cout << ", " << o.out << "/depth/";
  if (map) {
    mapping::saveMap(*map, o.map);
    std::cout << ", " << o.map;
  }
  if (o.report) std::cout << ", " << eval::writeHtmlReport(o.out);
  std::cout << "\n";
}

}  // namespace

void registerRunCommand(CLI::App& app) {
  auto o = std::make_shared<RunOptions>();
  CLI::App* cmd = app.add_subcommand("run", "Run the real-time pipeline over a recorded stereo sequence");
  cmd->add_option("--dataset", o->dataset,
                  "EuRoC folder (holding mav0/), KITTI sequence folder, the paper's layout, or a recording (ROS 1 bag, "
                  "MCAP, ROS 2 bag folder or .db3)")
      ->required();
  cmd->add_option("--format", o->format, "Dataset layout (auto: a file or a ROS 2 bag folder is a recording)")
      ->check(CLI::IsMember({"auto", "euroc", "kitti", "paper", "bag"}));
  cmd->add_option("--left", o->left, "Recording: left image topic (default: the first rig preset of bag.rigs found)");
  cmd->add_option("--right", o->right, "Recording: right image topic");
  cmd->add_option("--calibration", o->calibration,
                  "Recording: calibration file (OpenCV YAML, EuRoC cam0/sensor.yaml, KITTI calib.txt, the paper's "
                  "intrinsics.yaml); default: the cameras' CameraInfo topics");
  cmd->add_option(
      "--pose-topic", o->pose_topic,
      "Recording: poses (nav_msgs/Odometry, geometry_msgs/PoseStamped or TransformStamped, tf2_msgs/TFMessage)");
  cmd->add_option("--tf-parent", o->tf_parent, "Recording: the parent frame of the TF pair (--pose-topic /tf)");
  cmd->add_option("--tf-child", o->tf_child, "Recording: the child frame of the TF pair (--pose-topic /tf)");
  cmd->add_option("--trajectory", o->trajectory,
                  "Poses (TUM, EuRoC CSV, KITTI, OKVIS / SVIn2 CSV, OpenVINS); default: the dataset's ground truth");
  cmd->add_option("--trajectory-format", o->trajectory_format, "Trajectory format (default: detected)")
      ->check(CLI::IsMember({"tum", "euroc", "kitti", "okvis", "svin2", "openvins"}));
  cmd->add_option("--corrections", o->corrections,
                  "Loop-closure corrections: a folder (<time s>.tum: corrected poses of past frames, in the "
                  "trajectory's frame, each applied to the map when the run reaches its time) or SVIn2's "
                  "pose-graph file (svin_<date>.txt: IMU poses of its keyframes, applied at its last one)");
  cmd->add_option("--trajectory-times", o->trajectory_times,
                  "Times of KITTI poses (one a line, seconds); default: the KITTI sequence's times.txt");
  cmd->add_option("--pose-frame", o->pose_frame, "What the poses describe (default: the format's convention)")
      ->check(CLI::IsMember({"auto", "body", "camera"}));
  cmd->add_option("--config", o->config, "YAML configuration (sections stereo, fusion, run)");
  cmd->add_option("--fusion-views", o->fusion_views, "Fusion window (1 = no fusion: raw stereo points)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--max-frames", o->max_frames, "Process at most N frames (0 = all)")->check(CLI::NonNegativeNumber);
  cmd->add_flag("--write-depth", o->write_depth, "Write per-frame fused depth and confidence PFM maps");
  cmd->add_flag("--report", o->report, "Write OUT/report.html: timings, sample frames (implies --write-depth)");
  cmd->add_option("--voxel", o->voxel_m, "Keep one point per voxel of this size in points.ply (metres)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--keyframe-translation", o->keyframe_translation_m, "Keyframe threshold (metres)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--keyframe-rotation", o->keyframe_rotation_deg, "Keyframe threshold (degrees)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--out", o->out, "Output folder")->required();
  cmd->add_option("--map", o->map, "Integrate the fused points into an occupancy map saved here (.vdb, .bt, .ot)");
  cmd->callback([o] { run(*o); });
}

}  // namespace cenote::apps
