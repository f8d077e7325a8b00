#include "server/viewer/foxglove_protocol.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "common/error.h"

namespace cenote::server::viewer {
namespace {

std::string errorOf(const std::string& text) {
  try {
    parseClientMessage(text);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

std::vector<Channel> twoChannels() {
  return {{1, "/map", "json", "A", "{}", "jsonschema"}, {2, "/stats", "json", "B", "{}", "jsonschema"}};
}

TEST(FoxgloveProtocol, MessageDataFrameIsOpcodeSubscriptionAndTimeLittleEndianThenPayload) {
  const std::string frame = messageDataFrame(0x01020304u, 0x1122334455667788ull, "xyz");
  ASSERT_EQ(frame.size(), 16u);
  const std::string expected("\x01\x04\x03\x02\x01\x88\x77\x66\x55\x44\x33\x22\x11xyz", 16);
  EXPECT_EQ(frame, expected);
}

TEST(FoxgloveProtocol, ServerInfoAdvertiseAndStatusFollowTheSpec) {
  const auto info = nlohmann::json::parse(serverInfoMessage("cenote", "42"));
  EXPECT_EQ(info["op"], "serverInfo");
  EXPECT_EQ(info["name"], "cenote");
  EXPECT_EQ(info["sessionId"], "42");
  EXPECT_TRUE(info["capabilities"].is_array());
  const auto advertise = nlohmann::json::parse(advertiseMessage(twoChannels()));
  EXPECT_EQ(advertise["op"], "advertise");
  ASSERT_EQ(advertise["channels"].size(), 2u);
  EXPECT_EQ(advertise["channels"][1]["id"], 2);
  EXPECT_EQ(advertise["channels"][1]["topic"], "/stats");
  EXPECT_EQ(advertise["channels"][1]["schemaName"], "B");
  EXPECT_EQ(advertise["channels"][1]["schemaEncoding"], "jsonschema");
  const auto status = nlohmann::json::parse(statusMessage(StatusLevel::kError, "bad"));
  EXPECT_EQ(status, nlohmann::json({{"op", "status"}, {"level", 2}, {"message", "bad"}}));
}

TEST(FoxgloveProtocol, ParsesSubscribeAndUnsubscribe) {
  const ClientRequest s = parseClientMessage(
      R"({"op":"subscribe","subscriptions":[{"id":0,"channelId":3},{"id":7,"channelId":5}]})");
  ASSERT_EQ(s.subscribe.size(), 2u);
  EXPECT_EQ(s.subscribe[1].id, 7u);
  EXPECT_EQ(s.subscribe[1].channel_id, 5u);
  const ClientRequest u = parseClientMessage(R"({"op":"unsubscribe","subscriptionIds":[0,7]})");
  EXPECT_EQ(u.unsubscribe, (std::vector<uint32_t>{0, 7}));
}

TEST(FoxgloveProtocol, BadClientMessagesAreErrorsNamingWhatIsWrong) {
  EXPECT_EQ(errorOf("{not json"), "client message is not valid JSON");
  EXPECT_EQ(errorOf("[1,2]"), "client message must be a JSON object with an 'op' field");
  EXPECT_EQ(errorOf(R"({"subscriptions":[]})"), "client message has no string field 'op'");
  EXPECT_EQ(errorOf(R"({"op":"setParameters","parameters":[]})"),
            "op 'setParameters' is not supported by this server (it supports subscribe and unsubscribe)");
  EXPECT_EQ(errorOf(R"({"op":"subscribe"})"), "subscribe: missing field 'subscriptions'");
  EXPECT_EQ(errorOf(R"({"op":"subscribe","subscriptions":{}})"), "subscribe: field 'subscriptions' must be an array");
  EXPECT_EQ(errorOf(R"({"op":"subscribe","subscriptions":[{"id":1}]})"),
            "subscribe: subscriptions[0]: missing field 'channelId'");
  EXPECT_EQ(errorOf(R"({"op":"subscribe","subscriptions":[{"id":-1,"channelId":1}]})"),
            "subscribe: subscriptions[0]: field 'id' = -1 is outside [0, 4294967295]");
  EXPECT_EQ(errorOf(R"({"op":"subscribe","subscriptions":[{"id":"a","channelId":1}]})"),
            "subscribe: subscriptions[0]: field 'id' must be an integer, got \"a\"");
  EXPECT_EQ(errorOf(R"({"op":"unsubscribe","subscriptionIds":[1.5]})"),
            "unsubscribe: subscriptionIds[0]: field 'id' must be an integer, got 1.5");
}

TEST(FoxgloveProtocol, SubscriptionsRefuseUnknownChannelsReusedIdsAndUnknownUnsubscribes) {
  Subscriptions table;
  EXPECT_TRUE(
      table.apply(parseClientMessage(R"({"op":"subscribe","subscriptions":[{"id":5,"channelId":1}]})"), twoChannels())
          .empty());
  EXPECT_EQ(table.subscriptionOf(1), 5u);
  const std::vector<std::string> problems = table.apply(
      parseClientMessage(
          R"({"op":"subscribe","subscriptions":[{"id":6,"channelId":9},{"id":5,"channelId":2},{"id":6,"channelId":1}]})"),
      twoChannels());
  EXPECT_EQ(problems, (std::vector<std::string>{"subscribe: channel 9 is not advertised",
                                                "subscribe: subscription id 5 is already in use",
                                                "subscribe: channel 1 is already subscribed (as 5)"}));
  EXPECT_EQ(table.apply(parseClientMessage(R"({"op":"unsubscribe","subscriptionIds":[5,8]})"), twoChannels()),
            (std::vector<std::string>{"unsubscribe: no subscription 8"}));
  EXPECT_FALSE(table.subscriptionOf(1).has_value());
  EXPECT_TRUE(table.empty());
}

}  // namespace
}  // namespace cenote::server::viewer
