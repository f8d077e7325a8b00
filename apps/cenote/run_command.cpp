// `cenote run`: a recorded stereo sequence with poses in; fused points, depth maps and a timing
// report out, at camera rate.
#include <atomic>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include "apps/cenote/commands.h"
#include "apps/cenote/progress_bar.h"
#include "common/error.h"
#include "pipeline/dataset/stereo_dataset.h"
#include "common/yaml_section.h"
#include "eval/report/html_report.h"
#include "mapping/io/map_io.h"
#include "mapping/occupancy_map.h"
#include "pipeline/runner/runner.h"

namespace cenote::apps {
namespace {

std::atomic<bool> g_stop{false};

extern "C" void onInterrupt(int) { g_stop = true; }

struct RunOptions {
  std::string dataset, format = "auto", trajectory, trajectory_format, trajectory_times, pose_frame, config, out, map;
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

void run(const RunOptions& o) {
  pipeline::Runner runner(makeConfig(o));
  // The map stage: every fused batch is integrated (free space along each ray, a hit at its end).
  std::unique_ptr<mapping::OccupancyMap> map;
  pipeline::PointSink sink;
  if (!o.map.empty()) {
    mapping::mapFormatOf(o.map);  // an unknown extension fails now, not after the run
    map = std::make_unique<mapping::OccupancyMap>(mapConfig(o));
    sink = [&map](const PointBatch& batch) {
      if (!batch.empty()) map->integrate(batch);
    };
  }
  const std::unique_ptr<pipeline::StereoDataset> dataset = pipeline::openDataset(o.dataset,
                                                                                 pipeline::parseDatasetFormat(o.format));
  const pipeline::CameraTrajectory camera = pipeline::loadCameraTrajectory(
      *dataset, {o.trajectory, o.trajectory_format, o.trajectory_times, runner.config().run.pose_frame});
  const io::Trajectory& trajectory = camera.trajectory;
  std::cerr << dataset->describe() << "; trajectory " << trajectory.name() << " (" << trajectory.size() << " poses, "
            << camera.fileFrame() << " poses" << (camera.frame_assumed ? ", assumed" : "") << ")\n";
  if (camera.frame_assumed) std::cerr << "note: " << camera.note << "\n";

  g_stop = false;
  std::signal(SIGINT, onInterrupt);
  std::signal(SIGTERM, onInterrupt);
  ProgressBar bar("cenote run");
  pipeline::RunReport report = runner.run(*dataset, trajectory, o.out, g_stop, sink,
                                          [&bar](size_t done, size_t total) { bar.update(done, total); });
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);

  report.pose_frame = camera.fileFrame();
  report.pose_frame_assumed = camera.frame_assumed;
  report.pose_frame_hint = camera.note;
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
  cmd->add_option("--dataset", o->dataset, "EuRoC folder (holding mav0/) or KITTI sequence folder")->required();
  cmd->add_option("--format", o->format, "Dataset layout")->check(CLI::IsMember({"auto", "euroc", "kitti"}));
  cmd->add_option("--trajectory", o->trajectory, "Poses (TUM, EuRoC CSV or KITTI); default: the dataset's ground truth");
  cmd->add_option("--trajectory-format", o->trajectory_format, "Trajectory format (default: detected)")
      ->check(CLI::IsMember({"tum", "euroc", "kitti"}));
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
