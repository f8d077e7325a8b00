#include "server/viewer/foxglove_protocol.h"

#include <algorithm>
#include <nlohmann/json.hpp>

#include "common/error.h"

namespace cenote::server::viewer {
namespace {

using nlohmann::json;

uint32_t uint32Field(const json& object, const char* key, const std::string& where) {
  const auto it = object.find(key);
  if (it == object.end()) throw Error(where + ": missing field '" + key + "'");
  if (!it->is_number_integer() && !it->is_number_unsigned()) {
    throw Error(where + ": field '" + key + "' must be an integer, got " + it->dump());
  }
  const int64_t value = it->get<int64_t>();
  if (value < 0 || value > int64_t{0xffffffff}) {
    throw Error(where + ": field '" + key + "' = " + std::to_string(value) + " is outside [0, 4294967295]");
  }
  return static_cast<uint32_t>(value);
}

const json& arrayField(const json& object, const char* key, const std::string& where) {
  const auto it = object.find(key);
  if (it == object.end()) throw Error(where + ": missing field '" + key + "'");
  if (!it->is_array()) throw Error(where + ": field '" + key + "' must be an array");
  return *it;
}

}  // namespace

std::string serverInfoMessage(const std::string& name, const std::string& session_id) {
  return json{{"op", "serverInfo"},
              {"name", name},
              {"capabilities", json::array()},
              {"metadata", json::object()},
              {"sessionId", session_id}}
      .dump();
}

std::string advertiseMessage(const std::vector<Channel>& channels) {
  json list = json::array();
  for (const Channel& c : channels) {
    list.push_back({{"id", c.id},
                    {"topic", c.topic},
                    {"encoding", c.encoding},
                    {"schemaName", c.schema_name},
                    {"schema", c.schema},
                    {"schemaEncoding", c.schema_encoding}});
  }
  return json{{"op", "advertise"}, {"channels", list}}.dump();
}

std::string statusMessage(StatusLevel level, const std::string& message) {
  return json{{"op", "status"}, {"level", static_cast<int>(level)}, {"message", message}}.dump(
      -1, ' ', false, json::error_handler_t::replace);
}

std::string messageDataFrame(uint32_t subscription_id, uint64_t log_time_ns, std::string_view payload) {
  std::string frame(1 + 4 + 8 + payload.size(), '\0');
  frame[0] = 0x01;
  for (int i = 0; i < 4; ++i) frame[1 + i] = static_cast<char>((subscription_id >> (8 * i)) & 0xff);
  for (int i = 0; i < 8; ++i) frame[5 + i] = static_cast<char>((log_time_ns >> (8 * i)) & 0xff);
  std::copy(payload.begin(), payload.end(), frame.begin() + 13);
  return frame;
}

ClientRequest parseClientMessage(std::string_view text) {
  const json message = json::parse(text.begin(), text.end(), nullptr, false);
  if (message.is_discarded()) throw Error("client message is not valid JSON");
  if (!message.is_object()) throw Error("client message must be a JSON object with an 'op' field");
  const auto op = message.find("op");
  if (op == message.end() || !op->is_string()) throw Error("client message has no string field 'op'");
  const std::string name = op->get<std::string>();
  ClientRequest request;
  if (name == "subscribe") {
    const json& list = arrayField(message, "subscriptions", "subscribe");
    for (size_t i = 0; i < list.size(); ++i) {
      const std::string where = "subscribe: subscriptions[" + std::to_string(i) + "]";
      if (!list[i].is_object()) throw Error(where + " must be an object {id, channelId}");
      request.subscribe.push_back({uint32Field(list[i], "id", where), uint32Field(list[i], "channelId", where)});
    }
  } else if (name == "unsubscribe") {
    const json& list = arrayField(message, "subscriptionIds", "unsubscribe");
    for (size_t i = 0; i < list.size(); ++i) {
      const json wrapped = {{"id", list[i]}};
      request.unsubscribe.push_back(uint32Field(wrapped, "id", "unsubscribe: subscriptionIds[" + std::to_string(i) + "]"));
    }
  } else {
    throw Error("op '" + name + "' is not supported by this server (it supports subscribe and unsubscribe)");
  }
  return request;
}

std::vector<std::string> Subscriptions::apply(const ClientRequest& request, const std::vector<Channel>& channels) {
  std::vector<std::string> problems;
  for (const SubscribeItem& s : request.subscribe) {
    const bool known = std::any_of(channels.begin(), channels.end(),
                                   [&](const Channel& c) { return c.id == s.channel_id; });
    if (!known) {
      problems.push_back("subscribe: channel " + std::to_string(s.channel_id) + " is not advertised");
    } else if (by_id_.count(s.id) != 0) {
      problems.push_back("subscribe: subscription id " + std::to_string(s.id) + " is already in use");
    } else if (subscriptionOf(s.channel_id)) {
      problems.push_back("subscribe: channel " + std::to_string(s.channel_id) + " is already subscribed (as " +
                         std::to_string(*subscriptionOf(s.channel_id)) + ")");
    } else {
      by_id_[s.id] = s.channel_id;
    }
  }
  for (const uint32_t id : request.unsubscribe) {
    if (by_id_.erase(id) == 0) problems.push_back("unsubscribe: no subscription " + std::to_string(id));
  }
  return problems;
}

std::optional<uint32_t> Subscriptions::subscriptionOf(uint32_t channel_id) const {
  for (const auto& [id, channel] : by_id_)
    if (channel == channel_id) return id;
  return std::nullopt;
}

}  // namespace cenote::server::viewer
