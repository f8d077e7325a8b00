#include "server/server_config.h"

#include "common/yaml_section.h"

namespace cenote::server {

std::vector<ConfigError> ServerConfig::validate() const {
  ConfigErrors errors("server");
  errors.check(!listen.empty() && listen.find(':') != std::string::npos, "listen", listen, "must be HOST:PORT");
  errors.check(snapshot_period_s >= 0.0, "snapshot_period_s", snapshot_period_s, "must be >= 0 (0: only on shutdown)");
  errors.check(!snapshot_dir.empty(), "snapshot_dir", snapshot_dir, "must not be empty");
  errors.check(pose_wait_s >= 0.0 && pose_wait_s <= 60.0, "pose_wait_s", pose_wait_s, "must be in [0, 60]");
  errors.check(pose_history_s > 0.0, "pose_history_s", pose_history_s, "must be > 0");
  errors.check(max_frame_streams >= 1 && max_frame_streams <= 64, "max_frame_streams", max_frame_streams,
               "must be in [1, 64]");
  errors.check(max_subscriber_lag >= 1, "max_subscriber_lag", max_subscriber_lag, "must be >= 1");
  errors.check(threads >= 0 && threads <= 1024, "threads", threads, "must be in [0, 1024]");
  errors.check(limits.max_message_bytes >= 1 << 20 && limits.max_message_bytes <= (int64_t{1} << 31) - 1,
               "limits.max_message_bytes", limits.max_message_bytes, "must be in [1 MiB, 2 GiB)");
  errors.check(limits.max_batch >= 1, "limits.max_batch", limits.max_batch, "must be >= 1");
  errors.check(limits.max_points_per_batch >= 1, "limits.max_points_per_batch", limits.max_points_per_batch,
               "must be >= 1");
  errors.check(limits.max_box_voxels >= 1, "limits.max_box_voxels", limits.max_box_voxels, "must be >= 1");
  errors.check(limits.max_image_pixels >= 1, "limits.max_image_pixels", limits.max_image_pixels, "must be >= 1");
  return errors.take();
}

void ServerConfig::read(YamlSection& section) {
  section.read("listen", listen);
  section.read("token_file", token_file);
  section.read("snapshot_dir", snapshot_dir);
  section.read("snapshot_period_s", snapshot_period_s);
  section.read("snapshot_on_shutdown", snapshot_on_shutdown);
  section.read("calibration", calibration);
  section.read("frame_id", frame_id);
  section.read("pose_wait_s", pose_wait_s);
  section.read("pose_history_s", pose_history_s);
  section.read("max_frame_streams", max_frame_streams);
  section.read("max_subscriber_lag", max_subscriber_lag);
  section.read("threads", threads);
  YamlSection l = section.section("limits");
  l.read("max_message_bytes", limits.max_message_bytes);
  l.read("max_batch", limits.max_batch);
  l.read("max_points_per_batch", limits.max_points_per_batch);
  l.read("max_box_voxels", limits.max_box_voxels);
  l.read("max_image_pixels", limits.max_image_pixels);
  l.finish();
}

ServerSettings ServerSettings::load(const std::string& path) {
  ServerSettings settings;
  if (path.empty()) return settings;
  settings.pipeline = pipeline::PipelineConfig::load(path);  // stereo, fusion, run; checks the top level
  YamlSection root(loadYamlFile(path), "", path);
  YamlSection map = root.section("map");
  settings.map.read(map);
  map.finish();
  YamlSection server = root.section("server");
  settings.server.read(server);
  server.finish();
  return settings;
}

std::vector<ConfigError> ServerSettings::validate() const {
  std::vector<ConfigError> errors = pipeline.validate();
  for (auto& e : map.validate()) errors.push_back(std::move(e));
  for (auto& e : server.validate()) errors.push_back(std::move(e));
  return errors;
}

}  // namespace cenote::server
