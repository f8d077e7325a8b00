#include "server/server_config.h"

#include <sched.h>

#include <string>

#include "common/yaml_section.h"

namespace cenote::server {

std::vector<ConfigError> ServerConfig::validate() const {
  ConfigErrors errors("server");
  errors.check(!listen.empty() && listen.find(':') != std::string::npos, "listen", listen, "must be HOST:PORT");
  errors.check(snapshot_period_s >= 0.0, "snapshot_period_s", snapshot_period_s, "must be >= 0 (0: only on shutdown)");
  errors.check(!snapshot_dir.empty(), "snapshot_dir", snapshot_dir, "must not be empty");
  errors.checkRange("pose_wait_s", pose_wait_s, 0.0, 60.0);
  errors.check(pose_history_s > 0.0, "pose_history_s", pose_history_s, "must be > 0");
  errors.check(pose_max_jump_s > 0.0, "pose_max_jump_s", pose_max_jump_s, "must be > 0");
  errors.checkRange("max_frame_streams", max_frame_streams, 1, 64);
  errors.check(host.max_subscriber_lag >= 1, "max_subscriber_lag", host.max_subscriber_lag, "must be >= 1");
  errors.check(host.max_subscriber_bytes >= 4096, "max_subscriber_bytes", host.max_subscriber_bytes, "must be >= 4096");
  errors.check(read_token_file.empty() || !token_file.empty(), "read_token_file", read_token_file,
               "needs server.token_file (the operator's token) as well");
  errors.checkRange("completion_queues", completion_queues, 1, 64);
  errors.check(min_pollers >= 1 && min_pollers <= max_pollers, "min_pollers", min_pollers, "must be in [1, max_pollers]");
  errors.checkRange("max_pollers", max_pollers, 1, 1024);
  errors.check(time_slice_ms == 0.0 || (time_slice_ms >= 0.1 && time_slice_ms <= 100.0), "time_slice_ms", time_slice_ms,
               "must be 0 (kernel default) or in [0.1, 100]");
  errors.checkRange("query_cpus", query_cpus, 0, CPU_SETSIZE, " (0: gRPC threads not pinned)");
  errors.checkRange("ingest_nice", host.ingest_nice, 0, 19);
  errors.checkRange("derived_nice", host.derived_nice, 0, 19);
  errors.checkRange("derived_period_s", host.derived_period_s, 0.0, 3600.0);
  errors.check(host.derived_follow_s >= 0.0, "derived_follow_s", host.derived_follow_s, "must be >= 0");
  errors.check(limits.max_message_bytes >= 1 << 20 && limits.max_message_bytes <= (int64_t{1} << 31) - 1,
               "limits.max_message_bytes", limits.max_message_bytes, "must be in [1 MiB, 2 GiB)");
  errors.check(limits.max_batch >= 1, "limits.max_batch", limits.max_batch, "must be >= 1");
  errors.check(limits.max_points_per_batch >= 1, "limits.max_points_per_batch", limits.max_points_per_batch,
               "must be >= 1");
  errors.check(limits.max_box_voxels >= 1, "limits.max_box_voxels", limits.max_box_voxels, "must be >= 1");
  errors.check(limits.max_query_voxels >= 1, "limits.max_query_voxels", limits.max_query_voxels, "must be >= 1");
  errors.check(limits.max_snapshots >= 1, "limits.max_snapshots", limits.max_snapshots,
               "must be >= 1 (the previous session's map is always kept)");
  errors.check(limits.max_snapshot_bytes >= 0, "limits.max_snapshot_bytes", limits.max_snapshot_bytes,
               "must be >= 0 (0: no limit)");
  errors.check(limits.max_image_pixels >= 1, "limits.max_image_pixels", limits.max_image_pixels, "must be >= 1");
  errors.check(limits.max_poses >= 2, "limits.max_poses", limits.max_poses, "must be >= 2 (two poses bracket a frame)");
  errors.check(limits.max_subscribers >= 1, "limits.max_subscribers", limits.max_subscribers, "must be >= 1");
  errors.check(limits.max_snapshot_downloads >= 1, "limits.max_snapshot_downloads", limits.max_snapshot_downloads,
               "must be >= 1");
  errors.check(limits.max_ingest_streams >= 1, "limits.max_ingest_streams", limits.max_ingest_streams, "must be >= 1");
  const TransportConfig& t = transport;
  // Each stream holds a thread of the sync server: together they must leave the pollers and one
  // more for the planners' calls.
  const int stream_threads = max_frame_streams + limits.max_ingest_streams + limits.max_snapshot_downloads;
  errors.check(stream_threads + max_pollers < t.max_threads, "transport.max_threads", t.max_threads,
               "must exceed max_frame_streams + limits.max_ingest_streams + limits.max_snapshot_downloads + "
               "max_pollers (" +
                   std::to_string(stream_threads + max_pollers) + ")");
  errors.checkRange("transport.max_threads", t.max_threads, 8, 65536);
  errors.check(t.keepalive_time_s >= 1.0, "transport.keepalive_time_s", t.keepalive_time_s, "must be >= 1");
  errors.check(t.keepalive_timeout_s >= 0.1, "transport.keepalive_timeout_s", t.keepalive_timeout_s, "must be >= 0.1");
  errors.check(t.min_client_ping_interval_s >= 0.0, "transport.min_client_ping_interval_s", t.min_client_ping_interval_s,
               "must be >= 0");
  errors.check(t.max_connection_idle_s == 0.0 || t.max_connection_idle_s >= 1.0, "transport.max_connection_idle_s",
               t.max_connection_idle_s, "must be 0 (never) or >= 1");
  errors.check(t.max_connection_age_s == 0.0 || t.max_connection_age_s >= 1.0, "transport.max_connection_age_s",
               t.max_connection_age_s, "must be 0 (never) or >= 1");
  errors.check(t.max_connection_age_grace_s >= 0.0, "transport.max_connection_age_grace_s", t.max_connection_age_grace_s,
               "must be >= 0 (0: unbounded)");
  errors.checkRange("transport.shutdown_grace_s", t.shutdown_grace_s, 0.0, 60.0);
  std::vector<ConfigError> all = errors.take();
  for (auto& e : viewer.validate()) all.push_back(std::move(e));
  return all;
}

void ServerConfig::read(YamlSection& section) {
  section.read("listen", listen);
  section.read("token_file", token_file);
  section.read("read_token_file", read_token_file);
  section.read("snapshot_dir", snapshot_dir);
  section.read("snapshot_period_s", snapshot_period_s);
  section.read("snapshot_on_shutdown", snapshot_on_shutdown);
  section.read("calibration", calibration);
  section.read("frame_id", frame_id);
  section.read("pose_wait_s", pose_wait_s);
  section.read("pose_history_s", pose_history_s);
  section.read("pose_max_jump_s", pose_max_jump_s);
  section.read("max_frame_streams", max_frame_streams);
  section.read("max_subscriber_lag", host.max_subscriber_lag);
  section.read("max_subscriber_bytes", host.max_subscriber_bytes);
  section.read("completion_queues", completion_queues);
  section.read("min_pollers", min_pollers);
  section.read("max_pollers", max_pollers);
  section.read("time_slice_ms", time_slice_ms);
  section.read("query_cpus", query_cpus);
  section.read("ingest_nice", host.ingest_nice);
  section.read("derived_nice", host.derived_nice);
  section.read("derived_period_s", host.derived_period_s);
  section.read("derived_follow_s", host.derived_follow_s);
  section.read("frame_history", host.frame_history);
  YamlSection l = section.section("limits");
  l.read("max_message_bytes", limits.max_message_bytes);
  l.read("max_batch", limits.max_batch);
  l.read("max_points_per_batch", limits.max_points_per_batch);
  l.read("max_box_voxels", limits.max_box_voxels);
  l.read("max_query_voxels", limits.max_query_voxels);
  l.read("max_snapshots", limits.max_snapshots);
  l.read("max_snapshot_bytes", limits.max_snapshot_bytes);
  l.read("max_image_pixels", limits.max_image_pixels);
  l.read("max_poses", limits.max_poses);
  l.read("max_subscribers", limits.max_subscribers);
  l.read("max_snapshot_downloads", limits.max_snapshot_downloads);
  l.read("max_ingest_streams", limits.max_ingest_streams);
  l.finish();
  YamlSection t = section.section("transport");
  t.read("max_threads", transport.max_threads);
  t.read("keepalive_time_s", transport.keepalive_time_s);
  t.read("keepalive_timeout_s", transport.keepalive_timeout_s);
  t.read("keepalive_without_calls", transport.keepalive_without_calls);
  t.read("min_client_ping_interval_s", transport.min_client_ping_interval_s);
  t.read("max_connection_idle_s", transport.max_connection_idle_s);
  t.read("max_connection_age_s", transport.max_connection_age_s);
  t.read("max_connection_age_grace_s", transport.max_connection_age_grace_s);
  t.read("shutdown_grace_s", transport.shutdown_grace_s);
  t.finish();
  section.readSection("viewer", viewer);
}

ServerSettings ServerSettings::load(const std::string& path) {
  ServerSettings settings;
  if (path.empty()) return settings;
  settings.pipeline = pipeline::PipelineConfig::load(path);  // stereo, fusion, run; checks the top level
  YamlSection root(loadYamlFile(path), "", path);
  root.readSection("map", settings.map);
  root.readSection("server", settings.server);
  return settings;
}

std::vector<ConfigError> ServerSettings::validate() const {
  return concatConfigErrors({pipeline.validate(), map.validate(), server.validate()});
}

}  // namespace cenote::server
