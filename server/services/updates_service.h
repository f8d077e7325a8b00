// updates_service.h: Updates (proto/cenote/v1/updates.proto): the whole map first, in chunks of
// blocks, then every change as its changed blocks, read from the map when they are sent (so a
// mirror that applies them in order converges to the map). A subscriber that falls behind more
// than server.max_subscriber_lag changes or server.max_subscriber_bytes bytes of them gets the
// whole map again (resync) instead of a growing queue.
// An idle subscriber costs no thread: Subscribe runs on gRPC's callback API, and one sender thread
// builds every subscriber's next message when the change feed has one for it (one message in
// flight per subscriber, so gRPC buffers at most one). At most server.limits.max_subscribers at
// once (more: RESOURCE_EXHAUSTED). shutdown() ends every subscription with UNAVAILABLE (the
// client may reconnect to the restarted server). Admin.GetStats times a subscription's set-up
// (its checks and subscribing), not its life.
// Threads: gRPC's callback threads, the change feed's publisher and the sender thread.
#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <thread>

#include "cenote/v1/updates.grpc.pb.h"
#include "server/access/call_guard.h"
#include "server/host/map_host.h"

namespace cenote::server {

namespace detail {
class Subscriber;
}

class UpdatesService final : public v1::Updates::CallbackService {
 public:
  UpdatesService(MapHost& host, CallGuard& guard, int max_subscribers);
  ~UpdatesService() override;  // stops the sender (after the gRPC server is gone)
  UpdatesService(const UpdatesService&) = delete;
  UpdatesService& operator=(const UpdatesService&) = delete;

  grpc::ServerWriteReactor<v1::MapUpdate>* Subscribe(grpc::CallbackServerContext* context,
                                                     const v1::SubscribeRequest* request) override;

  // Ends every subscription (server shutdown): their calls end with UNAVAILABLE.
  void shutdown() { host_.feed().close(); }

 private:
  friend class detail::Subscriber;
  // Asks the sender thread to build and start `s`'s next message.
  void post(std::shared_ptr<detail::Subscriber> s);
  void sendLoop();

  MapHost& host_;
  CallGuard& guard_;
  const int max_subscribers_;
  std::atomic<int> subscribers_{0};
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<std::shared_ptr<detail::Subscriber>> queue_;
  bool stopping_ = false;
  std::thread sender_;
};

}  // namespace cenote::server
