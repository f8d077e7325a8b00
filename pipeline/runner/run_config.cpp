#include "pipeline/runner/run_config.h"

#include "common/enum_names.h"
#include "common/error.h"
#include "common/yaml_section.h"

namespace cenote::pipeline {

std::vector<ConfigError> RunConfig::validate() const {
  ConfigErrors errors("run");
  errors.checkRange("queue_depth", queue_depth, 1, 64);
  errors.check(pose_max_gap_s > 0.0, "pose_max_gap_s", pose_max_gap_s, "must be > 0");
  errors.check(keyframe_translation_m >= 0.0, "keyframe_translation_m", keyframe_translation_m, "must be >= 0");
  errors.check(keyframe_rotation_deg >= 0.0, "keyframe_rotation_deg", keyframe_rotation_deg, "must be >= 0");
  errors.check(points_voxel_m >= 0.0, "points_voxel_m", points_voxel_m, "must be >= 0 (0 = every point)");
  errors.check(points_format == "ply" || points_format == "pcd", "points_format", points_format, "must be ply or pcd");
  errors.check(outlier_neighbours >= 0, "outlier_neighbours", outlier_neighbours, "must be >= 0 (0 = off)");
  errors.check(outlier_stddev_mul > 0.0, "outlier_stddev_mul", outlier_stddev_mul, "must be > 0");
  errors.check(max_frames >= 0, "max_frames", max_frames, "must be >= 0 (0 = all)");
  return errors.take();
}

void RunConfig::read(YamlSection& section) {
  section.read("queue_depth", queue_depth);
  section.read("pose_max_gap_s", pose_max_gap_s);
  section.readName("pose_frame", pose_frame, parsePoseFrame);
  section.read("keyframe_translation_m", keyframe_translation_m);
  section.read("keyframe_rotation_deg", keyframe_rotation_deg);
  section.read("fuse", fuse);
  section.read("write_depth", write_depth);
  section.read("points_voxel_m", points_voxel_m);
  section.read("points_format", points_format);
  section.read("outlier_neighbours", outlier_neighbours);
  section.read("outlier_stddev_mul", outlier_stddev_mul);
  section.read("max_frames", max_frames);
}

std::string pointsFileName(const RunConfig& config) { return "points." + config.points_format; }

constexpr EnumName<PoseFrame> kPoseFrameNames[] = {
    {PoseFrame::kAuto, "auto"}, {PoseFrame::kBody, "body"}, {PoseFrame::kCamera, "camera"}};

const char* toString(PoseFrame frame) { return enumName(kPoseFrameNames, frame); }

PoseFrame parsePoseFrame(const std::string& name) {
  return parseEnumName(kPoseFrameNames, name, "run.pose_frame = " + name);
}

std::vector<ConfigError> PipelineConfig::validate() const {
  return concatConfigErrors({stereo.validate(), fusion.validate(), run.validate()});
}

PipelineConfig PipelineConfig::load(const std::string& path) {
  PipelineConfig config;
  const YAML::Node root = loadYamlFile(path);
  YamlSection top(root, "", path);
  top.readSection("stereo", config.stereo);
  top.readSection("fusion", config.fusion);
  top.readSection("run", config.run);
  // Sections of other components are read (and checked) by them.
  for (const char* other : {"map", "server", "sim", "eval", "bag"}) top.section(other);
  top.finish();
  return config;
}

}  // namespace cenote::pipeline
