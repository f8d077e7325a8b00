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
#include "server/viewer/viewer_config.h"
#include "pipeline/runner/run_config.h"

namespace cenote {
class YamlSection;
}

namespace cenote::server {

// What one request may ask for. Beyond a limit: RESOURCE_EXHAUSTED naming it.
struct RequestLimits {
  int64_t max_message_bytes = 64 << 20;           // of any request or reply (gRPC's receive limit)
  int64_t max_batch = 100000;                     // points / boxes / segments / rays in one query
  int64_t max_points_per_batch = 1000000;         // points in one ingested point batch
  int64_t max_box_voxels = 10000000;              // voxels in one box query or extract
  int64_t max_query_voxels = 100000000;           // voxels one query request may visit (all its items)
  int64_t max_snapshots = 10;                     // rotated snapshots kept (host/snapshotter.h)
  int64_t max_snapshot_bytes = int64_t{8} << 30;  // of map.vdb and the rotated ones; 0: no limit
  int64_t max_image_pixels = 4096 * 4096;         // of one stereo image
  int64_t max_poses = 100000;                     // streamed poses kept (200 Hz for over 8 minutes)
  int max_subscribers = 1024;                     // concurrent Updates.Subscribe calls
  int max_snapshot_downloads = 2;                 // concurrent Admin.DownloadSnapshot calls
  int max_ingest_streams = 8;                     // concurrent StreamPoses + StreamPoints calls
};

// gRPC's transport: threads, keepalive, connection lifetime, shutdown (server/main.cpp).
struct TransportConfig {
  int max_threads = 128;                    // gRPC's resource quota: threads of the sync server
                                            // (handlers and pollers); beyond, calls get RESOURCE_EXHAUSTED
  double keepalive_time_s = 10.0;           // ping a connection after this long without data
  double keepalive_timeout_s = 5.0;         // ... and close it when the ping is not answered in this
  bool keepalive_without_calls = true;      // ping connections with no call open too
  double min_client_ping_interval_s = 5.0;  // clients may ping this often (more: GOAWAY)
  double max_connection_idle_s = 600.0;     // close a connection without calls after this; 0: never
  double max_connection_age_s = 0.0;        // ask clients to reconnect after this; 0: never
  double max_connection_age_grace_s = 0.0;  // ... calls still open then get this long; 0: unbounded
  double shutdown_grace_s = 0.5;            // SIGTERM: streams are cancelled at once, other calls
                                            // in flight get this long to finish
};

struct ServerConfig {
  std::string listen = "127.0.0.1:50051";  // loopback unless asked otherwise
  std::string token_file;                  // operator's bearer token (first line); empty: no authentication
  std::string read_token_file;             // read-only token: Query, Updates, Admin.GetStats; needs token_file
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
  MapHostOptions host;             // keys max_subscriber_lag, max_subscriber_bytes, ingest_nice,
                                   // derived_nice, derived_period_s, derived_follow_s, frame_history
  RequestLimits limits;
  TransportConfig transport;
  viewer::ViewerConfig viewer;  // the live viewer (section viewer:); off unless viewer.listen is set

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
