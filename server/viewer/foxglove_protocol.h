// foxglove_protocol.h: the message layer of the Foxglove WebSocket protocol (subprotocol
// foxglove.websocket.v1, github.com/foxglove/ws-protocol docs/spec.md), without the WebSocket
// framing (viewer_server.cpp does that with Boost.Beast). The server sends serverInfo, advertise
// and status as JSON text; message data as binary: opcode 1, the subscription id (uint32), the log
// time (uint64 ns), both little-endian, then the channel's message. A client sends subscribe and
// unsubscribe; whatever else it sends, or anything malformed, is answered with an error status
// naming what was wrong, and the connection goes on.
// Threads: free functions over plain values; a Subscriptions table belongs to one connection.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cenote::server::viewer {

inline constexpr const char* kSubprotocol = "foxglove.websocket.v1";

struct Channel {
  uint32_t id = 0;
  std::string topic;
  std::string encoding;         // of the messages: "json"
  std::string schema_name;      // e.g. "foxglove.SceneUpdate"
  std::string schema;           // the schema's text
  std::string schema_encoding;  // "jsonschema"
};

enum class StatusLevel { kInfo = 0, kWarning = 1, kError = 2 };

std::string serverInfoMessage(const std::string& name, const std::string& session_id);
std::string advertiseMessage(const std::vector<Channel>& channels);
std::string statusMessage(StatusLevel level, const std::string& message);
// One binary message data frame.
std::string messageDataFrame(uint32_t subscription_id, uint64_t log_time_ns, std::string_view payload);

struct SubscribeItem {
  uint32_t id = 0;
  uint32_t channel_id = 0;
};
struct ClientRequest {
  std::vector<SubscribeItem> subscribe;  // op "subscribe"
  std::vector<uint32_t> unsubscribe;     // op "unsubscribe"
};
// Parses one text message of a client.
// @throws cenote::Error naming what is wrong: not JSON, not an object, no or unknown op, a field
//   missing or of the wrong type, an id outside uint32.
ClientRequest parseClientMessage(std::string_view text);

// The subscriptions of one connection: subscription id -> channel id.
class Subscriptions {
 public:
  // Applies a request; each item that cannot be applied (unknown channel, an id in use, a channel
  // already subscribed, an unknown subscription) is skipped and described in the result.
  std::vector<std::string> apply(const ClientRequest& request, const std::vector<Channel>& channels);
  // The subscription id of a channel, when the client subscribed to it.
  std::optional<uint32_t> subscriptionOf(uint32_t channel_id) const;
  bool empty() const { return by_id_.empty(); }

 private:
  std::map<uint32_t, uint32_t> by_id_;
};

}  // namespace cenote::server::viewer
