// updates_service.h: Updates (proto/cenote/v1/updates.proto): the whole map first, in chunks of
// blocks, then every change as its changed blocks, read from the map when they are sent (so a
// mirror that applies them in order converges to the map). A subscriber that falls behind more
// than server.max_subscriber_lag changes gets the whole map again (resync) instead of a growing
// queue.
// Threads: each call runs on its own handler thread until the client cancels or the server stops.
#pragma once

#include <atomic>

#include "cenote/v1/updates.grpc.pb.h"
#include "server/access/call_guard.h"
#include "server/host/map_host.h"

namespace cenote::server {

class UpdatesService final : public v1::Updates::Service {
 public:
  UpdatesService(MapHost& host, CallGuard& guard) : host_(host), guard_(guard) {}

  grpc::Status Subscribe(grpc::ServerContext* context, const v1::SubscribeRequest* request,
                         grpc::ServerWriter<v1::MapUpdate>* writer) override;

  // Ends every subscription (server shutdown): their calls return OK.
  void shutdown() { host_.feed().close(); }

 private:
  MapHost& host_;
  CallGuard& guard_;
};

}  // namespace cenote::server
