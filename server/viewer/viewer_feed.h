// viewer_feed.h: the viewer's clients as the feed sees them (ClientLink: subscriptions in, messages
// out, whatever carries them) and the worker that makes each client's messages every tick
// (viewer_server.h describes the channels, the budget and the back-pressure). No networking here:
// viewer_server.cpp supplies the links.
// Threads: a ClientLink's receive() from its network thread, send() from the worker; the worker
// is one thread of its own.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "server/viewer/foxglove_protocol.h"
#include "server/viewer/viewer_server.h"

namespace cenote::server::viewer {

enum ChannelId : uint32_t {
  kMapChannel = 1,
  kCameraChannel,
  kTrajectoryChannel,
  kCloudChannel,
  kFrontierChannel,
  kStatsChannel,
  kImageChannel,
  kDisparityChannel
};

// The channels every client is offered.
const std::vector<Channel>& viewerChannels();

class ClientLink {
 public:
  virtual ~ClientLink() = default;
  // Queues a WebSocket message (text or binary); any thread.
  virtual void send(std::string message, bool binary) = 0;
  // Bytes queued and not yet written to the socket.
  virtual size_t unsentBytes() const = 0;
  virtual bool isOpen() const = 0;

  // serverInfo, then the advertisement of every channel.
  void greet(const std::string& server_name, const std::string& session_id);
  // A text message from the client: subscriptions change; anything wrong is answered with an
  // error status naming it.
  void receiveText(std::string_view text);
  // A binary message: this server takes none (no clientPublish).
  void receiveBinary();
  // The subscription id of a channel now, if subscribed.
  std::optional<uint32_t> subscriptionOf(uint32_t channel) const;

 private:
  mutable std::mutex mutex_;
  Subscriptions subscriptions_;
};

class FeedWorker {
 public:
  FeedWorker(const ViewerConfig& config, const ViewerSources& sources);
  ~FeedWorker();
  void add(std::shared_ptr<ClientLink> link);
  void stop();
  uint64_t bytesSent() const { return bytes_sent_.load(); }
  size_t clients() const;

  struct Client;

 private:
  void loop();
  void tick(std::vector<std::shared_ptr<Client>>& clients, double dt_s);

  const ViewerConfig config_;
  const ViewerSources& sources_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::vector<std::shared_ptr<ClientLink>> arrived_;
  size_t clients_ = 0;
  bool stop_ = false;
  std::atomic<uint64_t> bytes_sent_{0};
  std::thread thread_;
};

}  // namespace cenote::server::viewer
