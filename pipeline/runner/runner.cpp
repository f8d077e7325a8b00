#include "pipeline/runner/runner.h"

#include <sys/resource.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "common/cpu_clock.h"
#include "common/error.h"
#include "common/size_format.h"
#include "common/thread_name.h"
#include "pipeline/calibration/rectifier.h"
#include "io/image/image_io.h"
#include "pipeline/fusion/outlier_removal.h"
#include "pipeline/runner/depth_index.h"
#include "pipeline/runner/frame_pipeline.h"
#include "pipeline/frame/frame_admission.h"
#include "pipeline/runner/point_output.h"
#include "pipeline/runner/team_cpu.h"

namespace cenote::pipeline {
namespace fs = std::filesystem;
namespace {

using Clock = std::chrono::steady_clock;

// The rows of the report's CPU table, in pipeline order.
constexpr const char* kCpuRows[] = {"read_rectify", "stereo", "fusion", "output", "map", "other", "total"};

// Dataset names of the frames in flight, by timestamp (a double copied unchanged through the
// stages, so equality holds). Entries leave as frames come out (or are passed by), so the table
// holds at most the frames between the reader and the output.
class FrameNames {
 public:
  void add(double t_s, std::string name) {
    std::lock_guard<std::mutex> lock(mutex_);
    names_.emplace(t_s, std::move(name));
  }
  std::string take(double t_s) {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = names_.find(t_s);
    std::string name = it != names_.end() ? it->second : std::to_string(std::llround(t_s * 1e9));
    names_.erase(names_.begin(), names_.upper_bound(t_s));
    return name;
  }

 private:
  std::mutex mutex_;
  std::map<double, std::string> names_;
};

}  // namespace

Runner::Runner(PipelineConfig config) : config_(std::move(config)) {
  throwIfInvalid(config_.validate(), "pipeline configuration");
}

RunReport Runner::run(const StereoDataset& dataset, const io::Trajectory& camera_trajectory, const std::string& out_dir,
                      const std::atomic<bool>& stop, const PointSink& sink, const ProgressCallback& progress) {
  const RunConfig& rc = config_.run;
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) throw Error("cannot create output folder " + out_dir + ": " + ec.message());
  if (rc.write_depth) fs::create_directories(fs::path(out_dir) / "depth", ec);
  PointOutput points((fs::path(out_dir) / pointsFileName(rc)).string(), rc.points_voxel_m);

  const Rectifier rectifier(dataset.calibration());

  const size_t total = rc.max_frames > 0 ? std::min<size_t>(dataset.size(), rc.max_frames) : dataset.size();
  RunReport report;
  report.frames_in = total;
  // Frames frame admission refused, by Admission; and unreadable ones. Written by the reader only,
  // read after it is joined. read_done is also read by the progress callback meanwhile.
  std::array<size_t, 4> refused{};
  size_t unreadable = 0;
  std::atomic<size_t> read_done{0};
  std::atomic<bool> interrupted{false};
  StageTimer read_timer, output_timer, sink_timer;
  // CPU time (cpu_clock.h): the reader's team, the output thread's own in each of its two stages,
  // and the output thread's OpenMP pool (the map's ray marching) as it was before the run.
  double read_cpu_ms = 0.0, output_cpu_ms = 0.0, sink_cpu_ms = 0.0;
  const double process_cpu0_ms = processCpuMs();
  const double pool_cpu0_ms = teamCpuMs() - threadCpuMs();
  FramePipeline stages(config_, rc.write_depth);
  StageFailure failure;
  FrameNames names;
  const auto start = Clock::now();

  const std::unique_ptr<FrameCursor> cursor = dataset.frames();
  size_t frames_read = 0;
  std::thread reader([&] {
    nameThisThread("cenote-read");
    try {
      FrameAdmission admission(rectifier, rc);
      for (size_t i = 0; (rc.max_frames == 0 || i < static_cast<size_t>(rc.max_frames)) && !failure.failed();
           ++i, ++read_done) {
        if (stop.load()) {
          interrupted = true;
          break;
        }
        const auto t0 = Clock::now();
        if (!cursor->next()) break;
        ++frames_read;
        const double t = cursor->timestamp();
        const FrameDecision decision = admission.decide(
            t, [&](double t_s) { return camera_trajectory.poseAt(t_s, rc.pose_max_gap_s); });
        if (decision.admission != Admission::kAdmitted) {
          ++refused[static_cast<size_t>(decision.admission)];
          continue;
        }
        PosedPair item;
        try {
          item = admission.admit(cursor->load(), decision.T_world_raw);
        } catch (const Error& e) {
          ++unreadable;
          std::fprintf(stderr, "\nwarning: frame %zu (t = %.6f s) skipped: %s\n", i, t, e.what());
          continue;
        }
        if (rc.write_depth) names.add(item.pair.t_s, cursor->frameName());
        read_timer.add(msSince(t0));
        if (!stages.push(std::move(item))) break;
      }
    } catch (...) {
      failure.set(std::current_exception());
      stages.abort();
    }
    read_cpu_ms = teamCpuMs();  // joined before it is read
    stages.close();
  });

  // Output on this thread.
  try {
    // The maps' camera beside them (depth_index.h), for `cenote fuse` on this folder.
    std::optional<DepthIndexWriter> depth_index;
    if (rc.write_depth) depth_index.emplace((fs::path(out_dir) / "depth" / "frames.csv").string());
    while (std::optional<FusedOutput> item = stages.pop()) {
      const auto t0 = Clock::now();
      const double cpu0_ms = threadCpuMs();
      if (rc.write_depth) {
        const std::string name = names.take(item->frame.t_s);
        const std::string base = (fs::path(out_dir) / "depth" / name).string();
        depth_index->add({name, item->frame.t_s, item->frame.K, item->frame.T_world_cam});
        io::writePfm(base + ".depth.pfm", item->frame.depth);
        io::writePfm(base + ".conf.pfm", item->frame.confidence);
        // The rectified left image beside its maps (JPEG: a tenth of a PNG's encoding time).
        if (!item->frame.color.empty()) io::writeImage(base + ".jpg", item->frame.color);
      }
      if (rc.outlier_neighbours > 0) {
        item->points = removeStatisticalOutliers(item->points, rc.outlier_neighbours, rc.outlier_stddev_mul);
      }
      points.append(item->points);
      output_timer.add(msSince(t0));
      const double cpu1_ms = threadCpuMs();
      output_cpu_ms += cpu1_ms - cpu0_ms;
      if (sink) {
        const auto t1 = Clock::now();
        sink(item->points, item->frame.T_world_cam);
        sink_timer.add(msSince(t1));
        sink_cpu_ms += threadCpuMs() - cpu1_ms;
      }
      stages.recycle(std::move(item->points));
      if (progress) progress(read_done.load(), total);
    }
  } catch (...) {
    failure.set(std::current_exception());
    stages.abort();
  }
  reader.join();
  while (stages.pop()) {
  }  // drains (and joins) after an output failure
  if (failure.failed() || stages.failed()) {
    try {
      points.close();  // keep what was written
    } catch (const Error&) {
    }
    failure.rethrow();
    stages.rethrowIfFailed();
  }
  points.close();
  if (progress) progress(read_done.load(), total);

  // A folder's frames are known before reading; a recording's once read (to the end, or max_frames).
  if (!interrupted) report.frames_in = frames_read;
  report.source_counts = cursor->counts();
  report.source_truncation = cursor->truncation();
  report.source_skipped = cursor->skipped();
  report.wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  report.frames_processed = stages.framesProcessed();
  report.frames_fused = stages.framesFused();
  report.skipped_out_of_order = refused[static_cast<size_t>(Admission::kOutOfOrder)];
  report.skipped_no_pose = refused[static_cast<size_t>(Admission::kNoPose)];
  report.skipped_not_keyframe = refused[static_cast<size_t>(Admission::kNotKeyframe)];
  report.skipped_unreadable = unreadable;
  report.points_written = points.pointsWritten();
  report.interrupted = interrupted;
  report.fps = report.wall_s > 0.0 ? static_cast<double>(report.frames_processed) / report.wall_s : 0.0;
  report.peak_memory_mb = peakMemoryMb();
  report.stages["read_rectify"] = read_timer.summary();
  report.stages["stereo"] = stages.stereoTiming();
  report.stages["fusion"] = stages.fusionTiming();
  report.stages["output"] = output_timer.summary();
  if (sink) report.stages["map"] = sink_timer.summary();
  // The output thread's OpenMP pool works only inside the sink (the map's ray marching).
  sink_cpu_ms += teamCpuMs() - threadCpuMs() - pool_cpu0_ms;
  const double frames = static_cast<double>(std::max<size_t>(report.frames_processed, 1));
  const double total_cpu_ms = processCpuMs() - process_cpu0_ms;
  const std::array<std::pair<const char*, double>, 5> cpu = {{{"read_rectify", read_cpu_ms},
                                                              {"stereo", stages.stereoCpuMs()},
                                                              {"fusion", stages.fusionCpuMs()},
                                                              {"output", output_cpu_ms},
                                                              {"map", sink_cpu_ms}}};
  double staged_ms = 0.0;
  for (const auto& [name, ms] : cpu) {
    if (report.stages.count(name)) report.cpu_ms_per_frame[name] = ms / frames;
    staged_ms += ms;
  }
  report.cpu_ms_per_frame["other"] = (total_cpu_ms - staged_ms) / frames;
  report.cpu_ms_per_frame["total"] = total_cpu_ms / frames;
  return report;
}

std::string RunReport::toJson() const {
  nlohmann::ordered_json j;
  j["frames_in"] = frames_in;
  j["frames_processed"] = frames_processed;
  j["frames_fused"] = frames_fused;
  j["frames_skipped"] = {{"out_of_order", skipped_out_of_order},
                         {"no_pose", skipped_no_pose},
                         {"not_keyframe", skipped_not_keyframe},
                         {"unreadable", skipped_unreadable}};
  if (!source_counts.empty() || !source_truncation.empty()) {
    nlohmann::ordered_json source = nlohmann::ordered_json::object();
    for (const auto& [name, count] : source_counts) source[name] = count;
    if (!source_truncation.empty()) source["truncation"] = source_truncation;
    if (!source_skipped.empty()) source["skipped"] = source_skipped;
    j["source"] = source;
  }
  j["points_written"] = points_written;
  j["interrupted"] = interrupted;
  if (!pose_frame.empty()) {
    j["pose_frame"] = pose_frame;
    j["pose_frame_assumed"] = pose_frame_assumed;
    if (!pose_frame_hint.empty()) j["pose_frame_hint"] = pose_frame_hint;
  }
  if (keyframes_only) j["pose_keyframes_only"] = pose_keyframes;
  j["wall_s"] = wall_s;
  j["fps"] = fps;
  j["peak_memory_mb"] = peak_memory_mb;
  nlohmann::ordered_json stage_json = nlohmann::ordered_json::object();
  for (const auto& [name, s] : stages) {
    stage_json[name] = {{"median_ms", s.median_ms}, {"p95_ms", s.p95_ms}, {"mean_ms", s.mean_ms}, {"frames", s.frames}};
  }
  j["stages"] = stage_json;
  nlohmann::ordered_json cpu_json = nlohmann::ordered_json::object();
  for (const char* name : kCpuRows) {
    if (const auto it = cpu_ms_per_frame.find(name); it != cpu_ms_per_frame.end()) cpu_json[name] = it->second;
  }
  j["cpu_ms_per_frame"] = cpu_json;
  return j.dump(2) + "\n";
}

std::string RunReport::toTable() const {
  std::ostringstream t;
  t.setf(std::ios::fixed);
  t.precision(1);
  t << "frames: " << frames_in << " in, " << frames_processed << " processed, " << frames_fused << " fused; skipped "
    << (skipped_out_of_order > 0 ? std::to_string(skipped_out_of_order) + " out of time order, " : "") << skipped_no_pose
    << " without pose, " << skipped_not_keyframe << " not keyframes, " << skipped_unreadable << " unreadable"
    << (interrupted ? " (interrupted)" : "") << "\n";
  if (keyframes_only) {
    t << "poses: keyframes only (" << pose_keyframes
      << "): frames between keyframes have no pose of their own and are skipped, as in the paper\n";
  }
  if (!source_counts.empty()) {
    t << "source:";
    for (const auto& [name, count] : source_counts) t << " " << name << " " << count;
    t << "\n";
  }
  if (!source_truncation.empty()) t << "source cut short: " << source_truncation << "\n";
  for (const std::string& damage : source_skipped) t << "source damaged: " << damage << "\n";
  t << "stage           median ms    p95 ms   frames   CPU ms/frame\n";
  for (const char* name : kCpuRows) {
    const auto it = stages.find(name);
    const auto cpu = cpu_ms_per_frame.find(name);
    if (it == stages.end() && cpu == cpu_ms_per_frame.end()) continue;
    char line[128];
    if (it != stages.end()) {
      std::snprintf(line, sizeof(line), "%-14s %10.1f %9.1f %8zu", name, it->second.median_ms, it->second.p95_ms,
                    it->second.frames);
    } else {
      std::snprintf(line, sizeof(line), "%-14s %10s %9s %8s", name, "", "", "");
    }
    t << line;
    if (cpu != cpu_ms_per_frame.end()) {
      std::snprintf(line, sizeof(line), " %14.1f", cpu->second);
      t << line;
    }
    t << "\n";
  }
  t << "end to end: " << fps << " fps over " << wall_s << " s, peak memory " << formatBytes(peak_memory_mb * 1048576.0)
    << ", " << points_written << " points\n";
  return t.str();
}

CameraTrajectory loadCameraTrajectory(const StereoDataset& dataset, const TrajectoryRequest& request) {
  TrajectorySource source;
  if (!request.path.empty()) {
    const io::TrajectoryFormat format = request.format.empty() ? io::detectTrajectoryFormat(request.path)
                                                               : io::parseTrajectoryFormat(request.format);
    source = dataset.trajectoryFile(request.path, format);
  } else if (const std::optional<TrajectorySource> own = dataset.defaultTrajectory()) {
    source = *own;
  } else {
    throw Error("no trajectory: " + dataset.describe() + " has no ground truth; give one with --trajectory");
  }
  if (!request.times.empty()) {
    if (source.format != io::TrajectoryFormat::kKitti) {
      throw Error("trajectory times " + request.times + ": only KITTI poses take a times file; " + source.path + " is " +
                  io::toString(source.format) + ", which carries its own timestamps");
    }
    source.kitti_times = request.times;
  }
  if (source.format == io::TrajectoryFormat::kKitti && source.kitti_times.empty()) {
    throw Error("trajectory " + source.path +
                ": KITTI poses carry no timestamps and this dataset has no times.txt; give them with "
                "--trajectory-times FILE (one time a line, seconds)");
  }
  CameraTrajectory out;
  out.file_describes_body = source.describes_body;
  if (request.pose_frame == PoseFrame::kBody) out.file_describes_body = true;
  if (request.pose_frame == PoseFrame::kCamera) out.file_describes_body = false;
  const Eigen::Isometry3d T_body_cam = dataset.T_body_cam();
  const bool extrinsics_matter = !T_body_cam.isApprox(Eigen::Isometry3d::Identity(), 1e-12);
  out.frame_assumed = request.pose_frame == PoseFrame::kAuto && source.frame_assumed && extrinsics_matter;
  if (out.frame_assumed) {
    char offset[96];
    std::snprintf(offset, sizeof(offset), "%.3f m and %.1f deg", T_body_cam.translation().norm(),
                  Eigen::AngleAxisd(T_body_cam.linear()).angle() * 180.0 / M_PI);
    out.note = std::string("poses of ") + source.path + " taken as " + out.fileFrame() + " poses: a " +
               io::toString(source.format) + " file does not say which frame it describes, and the camera sits " + offset +
               " from the body of " + dataset.describe() + "; pass --pose-frame body if they are body (IMU) poses";
  }
  const io::Trajectory trajectory = io::Trajectory::read(source.path, source.format, source.kitti_times);
  out.trajectory = out.file_describes_body ? trajectory.transformedBy(T_body_cam) : trajectory;
  out.keyframes_only = isKeyframeTrajectory(out.trajectory, dataset);
  return out;
}

bool isKeyframeTrajectory(const io::Trajectory& trajectory, const StereoDataset& dataset) {
  // The frames a trajectory spans are at most the dataset's size() (a recording's: its expected
  // pairs): as many poses as 3/4 of that are no keyframes, and a recording need not be read to know.
  if (trajectory.size() < 2 || 4 * trajectory.size() >= 3 * dataset.size()) return false;
  return isKeyframeTrajectory(trajectory, dataset.frameTimes());
}

bool isKeyframeTrajectory(const io::Trajectory& trajectory, std::vector<double> frames) {
  constexpr double kSameTime = 1e-6;
  const std::vector<io::StampedPose>& poses = trajectory.poses();
  if (poses.size() < 2 || frames.empty()) return false;
  std::sort(frames.begin(), frames.end());
  for (const io::StampedPose& p : poses) {
    const auto at = std::lower_bound(frames.begin(), frames.end(), p.t_s - kSameTime);
    if (at == frames.end() || *at > p.t_s + kSameTime) return false;  // a pose between frames: not a keyframe
  }
  const auto first = std::lower_bound(frames.begin(), frames.end(), poses.front().t_s - kSameTime);
  const auto last = std::upper_bound(frames.begin(), frames.end(), poses.back().t_s + kSameTime);
  return 4 * poses.size() < 3 * static_cast<size_t>(last - first);
}

io::Trajectory cameraTrajectory(const StereoDataset& dataset, const std::string& trajectory_path,
                                const std::string& trajectory_format, PoseFrame pose_frame) {
  return loadCameraTrajectory(dataset, {trajectory_path, trajectory_format, "", pose_frame}).trajectory;
}

double peakMemoryMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

}  // namespace cenote::pipeline
