// run_config.h: settings of the sequence runner (the `run:` section of the configuration), and
// the whole configuration of a run: stereo, fusion and run sections of one YAML file.
// Units: seconds, metres, degrees.
#pragma once

#include <string>
#include <vector>

#include "common/config_error.h"
#include "pipeline/fusion/fusion_config.h"
#include "pipeline/stereo/stereo_config.h"

namespace cenote {
class YamlSection;
}

namespace cenote::pipeline {

// What the poses of a trajectory describe; kAuto takes the file format's convention (TUM and
// KITTI: the camera, EuRoC ground truth: the body).
enum class PoseFrame { kAuto, kBody, kCamera };

struct RunConfig {
  int queue_depth = 2;           // frames waiting between two stages; >= 1
  double pose_max_gap_s = 0.25;  // interpolate a pose only between samples at most this far
                                 // apart (+1 us of slack); > 0. 2.5 periods of a 10 Hz stream
                                 // (the slowest VIO / ground truth): jitter and one dropped
                                 // sample pass, two in a row do not
  PoseFrame pose_frame = PoseFrame::kAuto;
  double keyframe_translation_m = 0.0;  // 0 and 0: every frame is processed (camera rate)
  double keyframe_rotation_deg = 0.0;   // else a frame moving less than both since the last is skipped
  bool fuse = true;                     // false: raw stereo points, no fusion (for comparisons);
                                        // the window size is fusion.num_views
  bool write_depth = false;             // per-frame depth / confidence PFM maps in out/depth/
  double points_voxel_m = 0.0;          // > 0: one point per voxel of this size in points.ply
  std::string points_format = "ply";    // ply: out/points.ply, streamed; pcd: out/points.pcd (PCL's
                                        // PCD, written at the end: see runner/point_output.h)
  int outlier_neighbours = 0;           // > 0: PCL's statistical outlier removal of each fused frame
                                        // over this many neighbours (fusion/outlier_removal.h), before
                                        // the points file and the map; 0: off
  double outlier_stddev_mul = 1.0;      // ... keeps points within mean + this many standard deviations
  int max_frames = 0;                   // 0 = all

  std::vector<ConfigError> validate() const;
  void read(YamlSection& section);
};

// "points.ply" or "points.pcd", as points_format says.
std::string pointsFileName(const RunConfig& config);

const char* toString(PoseFrame frame);
// "auto", "body" or "camera". @throws cenote::Error otherwise.
PoseFrame parsePoseFrame(const std::string& name);

// Everything a run needs, read from one YAML file (sections stereo, fusion, run).
struct PipelineConfig {
  StereoConfig stereo;
  FusionConfig fusion;
  RunConfig run;

  // Every failed rule of every section.
  std::vector<ConfigError> validate() const;
  // @throws cenote::Error for a missing or malformed file, or an unknown key (file and key named).
  //         Sections absent from the file keep their defaults; other top-level sections (map,
  //         server, sim) are left to their own readers.
  static PipelineConfig load(const std::string& path);
};

}  // namespace cenote::pipeline
