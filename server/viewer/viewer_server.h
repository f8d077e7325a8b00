// viewer_server.h: the live viewer endpoint: one TCP port that serves the Foxglove WebSocket
// protocol (foxglove_protocol.h; Foxglove and Lichtblick connect to ws://HOST:PORT) and, over
// plain HTTP GET, the browser viewer's files (web/, bundled at build time).
// Channels (ids fixed): 1 /map (foxglove.SceneUpdate, block_sync.h), 2 /camera
// (foxglove.FrameTransform world -> camera), 3 /trajectory (foxglove.PosesInFrame), 4 /cloud
// (foxglove.PointCloud, the latest fused batch), 5 /frontiers (foxglove.SceneUpdate), 6 /stats
// (cenote.MapStats), 7 /camera/image and 8 /camera/disparity (foxglove.CompressedImage). Each client is sent at most budget_bytes_per_s (a token bucket holding one
// second), and while its socket has more than a second's worth unsent nothing new is made for it:
// the map waits as a set of dirty blocks, the other channels as their newest value.
// Security: with a certificate (ViewerConfig::tls_cert_file) every connection is TLS (https://,
// wss://; TLS 1.2 or later) and one that is not is dropped at the handshake. The WebSocket needs one of the server's tokens when it has any (header `Authorization: Bearer
// <token>` or `?token=<token>` in the URL: browsers cannot set headers), else HTTP 401; the page's
// files are public (they hold no map data). Client messages the protocol does not allow get an
// error status message, never a closed connection.
// Threads: one network thread (Boost.Asio, named viewer-net) and one thread that makes every
// client's messages (viewer-feed),
// both started by the constructor, stopped by stop() or the destructor. With no client connected
// the feed holds no change subscription and the worker sleeps: ingest pays nothing for it.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "mapping/frontier/frontier_map.h"
#include "mapping/occupancy_map.h"
#include "server/viewer/live_feed.h"
#include "server/viewer/viewer_config.h"

namespace cenote::server::viewer {

// The map's changes as the viewer reads them: the server's change feed, or none (a saved map).
class ChangeSource {
 public:
  enum class Next { kChange, kResync, kNone, kClosed };
  virtual ~ChangeSource() = default;
  // Without waiting: the next change's blocks, kResync (changes were lost: send everything) or kNone.
  virtual Next poll(std::vector<mapping::BlockIndex>& blocks) = 0;
};

struct StageRate {
  std::string name;
  double median_ms = 0.0;
  uint64_t frames = 0;
};

struct ViewerSources {
  const mapping::OccupancyMap* map = nullptr;  // must outlive the server
  // Subscribes to the map's changes; empty: the map does not change.
  std::function<std::unique_ptr<ChangeSource>()> subscribe;
  LiveFeed* live = nullptr;  // camera and cloud; null: those channels stay silent
  // Frontier clusters sorted from a position; empty: none.
  std::function<std::vector<mapping::FrontierCluster>(const Eigen::Vector3d&)> frontiers;
  std::function<std::vector<StageRate>()> stages;  // per-stage timings; empty: none
  std::function<uint64_t()> batches;               // batches integrated; empty: none
  std::string frame_id = "world";
  // Tokens that let a client in, any one of them (cenote-server's operator and read-only tokens:
  // viewing is reading); none: no authentication.
  std::vector<std::string> tokens;
  std::string server_name = "cenote";
};

class ViewerServer {
 public:
  // Listens on config.listen at once.
  // @throws cenote::Error when it cannot (address in use, bad host).
  ViewerServer(const ViewerConfig& config, ViewerSources sources);
  ~ViewerServer();
  ViewerServer(const ViewerServer&) = delete;
  ViewerServer& operator=(const ViewerServer&) = delete;

  int port() const;
  bool usesTls() const;
  // How to reach it at `host`: "http://HOST:PORT/ (Foxglove: ws://HOST:PORT)", https and wss with TLS.
  std::string urls(const std::string& host) const;
  // Closes every connection and stops both threads (idempotent).
  void stop();
  uint64_t bytesSent() const;  // WebSocket payload bytes written to all clients so far
  size_t clients() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace cenote::server::viewer
