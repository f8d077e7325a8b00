// server_config.h: settings of `cenote-server` (the `server:` section of the configuration file)
// and the whole configuration the server runs with: pipeline (stereo, fusion, run), map, server.
// Units: seconds, bytes, voxels. Command-line flags override the file (server/main.cpp).
// Threads: plain values.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/config_error.h"
#include "mapping/map_config.h"
#include "server/host/map_host_options.h"
#include "pipeline/runner/run_config.h"

namespace cenote {
class YamlSection;
}

namespace cenote::server {

// What one request may ask for. Beyond a limit: RESOURCE_EXHAUSTED naming it.
struct RequestLimits {
  int64_t max_message_bytes = 64 << 20;    // of any request or reply (gRPC's receive limit)
  int64_t max_batch = 100000;              // points / boxes / segments / rays in one query
  int64_t max_points_per_batch = 1000000;  // points in one ingested point batch
  int64_t max_box_voxels = 10000000;       // voxels in one box query or extract
  int64_t max_query_voxels = 100000000;    // voxels one query request may visit (all its items)
  int64_t max_snapshots = 10;              // rotated snapshots kept (host/snapshotter.h)
  int64_t max_snapshot_bytes = 1LL << 33;  // 8 GiB of map.vdb and the rotated ones; 0: no limit
  int64_t max_image_pixels = 4096 * 4096;  // of one stereo image
  int64_t max_poses = 100000;              // streamed poses kept (200 Hz for over 8 minutes)
};

struct ServerConfig {
  std::string listen = "127.0.0.1:50051";  // loopback unless asked otherwise
  std::string token_file;                  // bearer token (first line); empty: no authentication
  std::string snapshot_dir = "snapshots";  // Admin.Snapshot writes under it; the periodic and
                                           // shutdown snapshot is <snapshot_dir>/map.vdb
  double snapshot_period_s = 60.0;         // 0: only on shutdown and on request
  bool snapshot_on_shutdown = true;
  std::string calibration;         // stereo rig for StreamFrames: calibration YAML or dataset folder
  std::string frame_id = "world";  // the map's frame, written into snapshots
  double pose_wait_s = 1.0;        // a frame without pose waits this long for a later pose
  double pose_history_s = 60.0;    // poses older than this (before the newest) are dropped
  double pose_max_jump_s = 60.0;   // a pose further than this after the stream's clock is refused
  int max_frame_streams = 2;       // concurrent StreamFrames calls (each runs a pipeline)
  int completion_queues = 1;       // gRPC's sync server: completion queues,
  int min_pollers = 2;             //   and threads polling each (handlers run on them;
  int max_pollers = 16;            //   more are made while calls wait; see server/main.cpp)
  double time_slice_ms = 0.1;      // CPU time slice of every server thread (cpu_scheduling.h);
                                   // 0: the kernel's default
  int query_cpus = 1;              // CPUs of gRPC's threads, the last ones (cpu_placement.h);
                                   // 0: not pinned
  MapHostOptions host;             // keys max_subscriber_lag, ingest_nice, derived_nice,
                                   // derived_period_s, derived_follow_s
  RequestLimits limits;

  std::vector<ConfigError> validate() const;
  // Reads keys of a `server:` section; unknown keys are errors.
  void read(YamlSection& section);
};

// Everything the server runs with.
struct ServerSettings {
  pipeline::PipelineConfig pipeline;
  mapping::MapConfig map;
  ServerConfig server;

  // Reads `path` (every section optional, unknown keys are errors); defaults without a path.
  // @throws cenote::Error naming the file and key of the first bad entry.
  static ServerSettings load(const std::string& path);
  // Every failed rule of every section, each naming its key.
  std::vector<ConfigError> validate() const;
};

}  // namespace cenote::server
