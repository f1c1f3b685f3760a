// The Foxglove WebSocket protocol's messages (pc_server/foxglove/ws_protocol):
// the spec's examples parsed, every malformed form named, the server's
// messages built byte for byte.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "pc_server/foxglove/ws_protocol.hpp"

using namespace inspect::server::foxglove;
using Json = nlohmann::json;

TEST(WsProtocol, ChoosesEitherSubprotocolName) {
  EXPECT_EQ(chooseSubprotocol("foxglove.websocket.v1"), "foxglove.websocket.v1");
  EXPECT_EQ(chooseSubprotocol("foxglove.sdk.v1"), "foxglove.sdk.v1");
  EXPECT_EQ(chooseSubprotocol("foxglove.sdk.v1,foxglove.websocket.v1"), "foxglove.websocket.v1");
  EXPECT_EQ(chooseSubprotocol(" other , foxglove.sdk.v1 "), "foxglove.sdk.v1");
  EXPECT_EQ(chooseSubprotocol("foxglove.websocket.v2"), "");
  EXPECT_EQ(chooseSubprotocol(""), "");
}

TEST(WsProtocol, ParsesTheSpecsClientMessages) {
  auto p = parseClientText(R"({"op":"subscribe","subscriptions":[{"id":0,"channelId":3},{"id":1,"channelId":5}]})");
  ASSERT_TRUE(p.ok()) << p.error;
  const auto& s = std::get<Subscribe>(p.message);
  ASSERT_EQ(s.subscriptions.size(), 2u);
  EXPECT_EQ(s.subscriptions[1].id, 1u);
  EXPECT_EQ(s.subscriptions[1].channel_id, 5u);

  p = parseClientText(R"({"op":"unsubscribe","subscriptionIds":[0,1]})");
  ASSERT_TRUE(p.ok());
  EXPECT_EQ(std::get<Unsubscribe>(p.message).subscription_ids, (std::vector<uint32_t>{0, 1}));

  p = parseClientText(R"({"op":"advertise","channels":[{"id":2,"topic":"/cmd_vel","encoding":"json","schemaName":"geometry_msgs/Twist"}]})");
  ASSERT_TRUE(p.ok()) << p.error;
  EXPECT_EQ(std::get<ClientAdvertise>(p.message).channels.at(0).topic, "/cmd_vel");

  p = parseClientText(R"({"op":"fetchAsset","uri":"package://x","requestId":1})");
  ASSERT_TRUE(p.ok());
  EXPECT_EQ(std::get<UnsupportedOp>(p.message).capability, "assets");
}

TEST(WsProtocol, NamesWhatIsWrongWithText) {
  EXPECT_EQ(parseClientText("{nope").error, "malformed JSON");
  EXPECT_EQ(parseClientText("[1,2]").error, "a text message must be a JSON object");
  EXPECT_EQ(parseClientText(R"({"op":7})").error, "a text message needs a string \"op\"");
  EXPECT_EQ(parseClientText(R"({"op":"dance"})").error, "unknown op \"dance\"");
  EXPECT_EQ(parseClientText(R"({"op":"subscribe"})").error, "subscribe: missing \"subscriptions\"");
  EXPECT_EQ(parseClientText(R"({"op":"subscribe","subscriptions":{}})").error,
            "subscribe: \"subscriptions\" must be an array");
  EXPECT_EQ(parseClientText(R"({"op":"subscribe","subscriptions":[{"id":-1,"channelId":1}]})").error,
            "subscribe: subscriptions[0].id -1 is not a uint32");
  EXPECT_EQ(parseClientText(R"({"op":"subscribe","subscriptions":[{"id":1.5,"channelId":1}]})").error,
            "subscribe: subscriptions[0].id must be an integer");
  EXPECT_EQ(parseClientText(R"({"op":"unsubscribe","subscriptionIds":[4294967296]})").error,
            "unsubscribe: subscriptionIds[0] 4294967296 is not a uint32");
  EXPECT_EQ(parseClientText(R"({"op":"advertise","channels":[{"id":1,"topic":"/a","encoding":"json"}]})").error,
            "advertise: channels[0]: missing \"schemaName\"");
}

TEST(WsProtocol, ParsesAndRefusesBinaryMessages) {
  const std::string data("\x01\x07\x00\x00\x00{\"a\":1}", 12);
  auto p = parseClientBinary(data);
  ASSERT_TRUE(p.ok()) << p.error;
  EXPECT_EQ(std::get<ClientMessageData>(p.message).channel_id, 7u);
  EXPECT_EQ(std::get<ClientMessageData>(p.message).payload, "{\"a\":1}");

  const std::string call("\x02\x04\x00\x00\x00\x09\x00\x00\x00\x04\x00\x00\x00json{}", 19);
  p = parseClientBinary(call);
  ASSERT_TRUE(p.ok()) << p.error;
  const auto& c = std::get<ServiceCallRequest>(p.message);
  EXPECT_EQ(c.service_id, 4u);
  EXPECT_EQ(c.call_id, 9u);
  EXPECT_EQ(c.encoding, "json");
  EXPECT_EQ(c.payload, "{}");

  EXPECT_EQ(parseClientBinary("").error, "empty binary message");
  EXPECT_EQ(parseClientBinary(std::string("\x01\x07", 2)).error,
            "client message data: 2 bytes, needs at least 5 (opcode, channel id)");
  EXPECT_EQ(parseClientBinary(std::string("\x02\x01\x00\x00\x00\x01\x00\x00\x00\xff\x00\x00\x00", 13)).error,
            "service call request: encoding length 255 runs past the message (13 bytes)");
  EXPECT_EQ(parseClientBinary("\x7f").error, "unknown binary opcode 0x7f");
}

TEST(WsProtocol, BuildsServerMessages) {
  const auto info = Json::parse(serverInfoJson("pc_server", {"clientPublish", "services"}, {"json"}, "123"));
  EXPECT_EQ(info["op"], "serverInfo");
  EXPECT_EQ(info["capabilities"], Json::array({"clientPublish", "services"}));
  EXPECT_EQ(info["supportedEncodings"], Json::array({"json"}));
  EXPECT_EQ(info["sessionId"], "123");
  EXPECT_FALSE(info["metadata"].contains("ROS_DISTRO"));  // would switch the app into a ROS profile

  const auto adv = Json::parse(advertiseJson({{3, "/robot1/scene", "protobuf", "foxglove.SceneUpdate", "AAA=", "protobuf"}}));
  EXPECT_EQ(adv["channels"][0]["id"], 3);
  EXPECT_EQ(adv["channels"][0]["schemaEncoding"], "protobuf");

  const auto svc = Json::parse(advertiseServicesJson({{1, "/stop", "inspect/Stop", "{}", "{}"}}));
  EXPECT_EQ(svc["services"][0]["request"]["encoding"], "json");
  EXPECT_EQ(svc["services"][0]["request"]["schemaEncoding"], "jsonschema");
  EXPECT_EQ(svc["services"][0]["response"]["schemaName"], "inspect/Stop_Response");

  // A status with text cut mid-character still is valid JSON.
  EXPECT_FALSE(Json::parse(statusJson(StatusLevel::kError, std::string("bad \xe2\x82", 6)), nullptr, false).is_discarded());

  const std::string h = messageDataHeader(0x01020304, 0x1112131415161718ULL);
  ASSERT_EQ(h.size(), kMessageDataHeaderBytes);
  EXPECT_EQ(h, std::string("\x01\x04\x03\x02\x01\x18\x17\x16\x15\x14\x13\x12\x11", 13));
  EXPECT_EQ(serviceCallResponse(2, 3, "json", "{}"),
            std::string("\x03\x02\x00\x00\x00\x03\x00\x00\x00\x04\x00\x00\x00json{}", 19));
}
