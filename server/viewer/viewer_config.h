// viewer_config.h: settings of the live viewer feed (`server.viewer` in the configuration file):
// the Foxglove WebSocket endpoint and browser page of viewer_server.h.
// Units: bytes per second, seconds, points. Threads: plain values.
#pragma once

#include <string>
#include <vector>

#include "common/config_error.h"

namespace cenote {
class YamlSection;
}

namespace cenote::server::viewer {

struct ViewerConfig {
  std::string listen;                 // HOST:PORT of the viewer; empty: no viewer (the default).
                                      // A host other than loopback serves the whole network.
  double budget_bytes_per_s = 1.0e6;  // what one client is sent at most, averaged over a second
  double tick_s = 0.05;               // how often each client's feed is brought up to date
  double stats_period_s = 1.0;        // map statistics and frontiers at most this often
  double refresh_s = 5.0;             // a block whose occupied voxels did not change is sent again (colours,
                                      // probabilities) at most this often, budget allowing
  double resend_s = 1.0;              // a block the client has is sent again at most this often while the map changes it
  int max_cloud_points = 5000;        // the latest fused cloud, thinned to at most this many points
  int max_trajectory_poses = 1000;    // camera poses kept and sent (the oldest are dropped)
  double image_hz = 1.0;              // the camera images (left, disparity preview) at most this often; 0: none
  int image_max_width_px = 640;       // ... scaled down to at most this width
  std::string color_by = "image";     // cube colours: "image" (the map's colour) or "height"
  std::string web_dir;                // the browser page's files; empty: those the build made
  std::string tls_cert_file;          // PEM certificate chain: the port serves https:// and wss:// only;
  std::string tls_key_file;           // ... its PEM private key. Both empty: plain TCP (cenote-server
                                      // then takes its own --tls-cert / --tls-key)

  std::vector<ConfigError> validate() const;  // keys named server.viewer.*
  // Reads the keys of a `viewer:` section; unknown keys are errors.
  void read(YamlSection& section);
  bool enabled() const { return !listen.empty(); }
};

}  // namespace cenote::server::viewer
