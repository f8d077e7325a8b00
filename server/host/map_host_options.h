// map_host_options.h: how the server's MapHost (map_host.h) runs its writer and derived threads
// and its change feed. Part of the `server:` configuration section (server_config.h), kept in a
// header of its own so that the configuration does not pull in the map.
// Units: seconds; nice values 0..19 (higher: lower CPU priority).
#pragma once

#include <cstddef>

namespace cenote::server {

struct MapHostOptions {
  size_t max_subscriber_lag = 64;         // changes queued per update subscriber before it is resynced
  size_t max_subscriber_bytes = 8 << 20;  // ... or bytes of them (change_feed.h: bytesOf)
  int ingest_nice = 5;                    // CPU priority of integration below the query handlers
  int derived_nice = 10;                  // ... of the distance field and frontier updates
  double derived_period_s = 1.0;          // they follow the map at least this often (and at once when a
                                          // distance / frontier query waits); 0: after every change
  double derived_follow_s = 30.0;         // ... while such a query came in the last this many seconds;
                                          // otherwise they catch up on the next one
  bool frame_history = false;             // keep integrated frames (map.history_*) for Ingest.CorrectPoses
};

}  // namespace cenote::server
