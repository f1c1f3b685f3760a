#pragma once
// The Foxglove WebSocket protocol's messages (foxglove.websocket.v1, the spec
// of foxglove/ws-protocol, docs/foxglove.md): the client's JSON and binary
// messages parsed into plain structs, the server's built from them. Pure: no
// sockets, no clock, no state (the fuzz harness feeds the parsers).
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace inspect::server::foxglove {

/// The subprotocol names a client may offer (both are the same protocol:
/// the spec's, and the Foxglove SDK's rename of it).
inline constexpr std::string_view kSubprotocol = "foxglove.websocket.v1";
inline constexpr std::string_view kSubprotocolSdk = "foxglove.sdk.v1";
/// The subprotocol to answer a handshake with, from the Sec-WebSocket-Protocol
/// header's comma-separated tokens; "" when neither name is offered.
std::string chooseSubprotocol(std::string_view offered);

// --- server -> client ---------------------------------------------------

/// A channel the server publishes on.
struct Channel {
  uint32_t id = 0;
  std::string topic;
  std::string encoding;         // "protobuf", "json"
  std::string schema_name;      // e.g. "foxglove.SceneUpdate"
  std::string schema;           // protobuf: base64 FileDescriptorSet; json: the JSON Schema text
  std::string schema_encoding;  // "protobuf", "jsonschema"
};

/// A service the server offers; request and response are JSON with a JSON Schema.
struct Service {
  uint32_t id = 0;
  std::string name;             // e.g. "/robot/stop"
  std::string type;             // e.g. "inspect/Stop"
  std::string request_schema;   // JSON Schema text
  std::string response_schema;
  bool urgent = false;          // never refused for the rate (stop, e-stop); not sent to clients
};

enum class StatusLevel { kInfo = 0, kWarning = 1, kError = 2 };

std::string serverInfoJson(const std::string& name, const std::vector<std::string>& capabilities,
                           const std::vector<std::string>& supported_encodings, const std::string& session_id,
                           const std::map<std::string, std::string>& metadata = {});
std::string advertiseJson(const std::vector<Channel>& channels);
std::string unadvertiseJson(const std::vector<uint32_t>& ids);
std::string advertiseServicesJson(const std::vector<Service>& services);
std::string statusJson(StatusLevel level, const std::string& message, const std::string& id = "");
std::string serviceCallFailureJson(uint32_t service_id, uint32_t call_id, const std::string& message);
/// Opcode 0x01 Message Data: opcode, subscription id, timestamp (ns), then the payload.
inline constexpr std::size_t kMessageDataHeaderBytes = 13;
std::string messageDataHeader(uint32_t subscription_id, uint64_t timestamp_ns);
/// Opcode 0x03 Service Call Response.
std::string serviceCallResponse(uint32_t service_id, uint32_t call_id, std::string_view encoding,
                                std::string_view payload);

// --- client -> server ---------------------------------------------------

struct Subscribe {
  struct Item {
    uint32_t id = 0;          // the client's subscription id
    uint32_t channel_id = 0;
  };
  std::vector<Item> subscriptions;
};
struct Unsubscribe {
  std::vector<uint32_t> subscription_ids;
};
/// A channel a client will publish on (capability clientPublish).
struct ClientChannel {
  uint32_t id = 0;
  std::string topic;
  std::string encoding;
  std::string schema_name;
};
struct ClientAdvertise {
  std::vector<ClientChannel> channels;
};
struct ClientUnadvertise {
  std::vector<uint32_t> channel_ids;
};
/// Binary 0x01: a message on a client channel. `payload` points into the parsed bytes.
struct ClientMessageData {
  uint32_t channel_id = 0;
  std::string_view payload;
};
/// Binary 0x02: a service call. `payload` points into the parsed bytes.
struct ServiceCallRequest {
  uint32_t service_id = 0;
  uint32_t call_id = 0;
  std::string encoding;
  std::string_view payload;
};
/// An op of the protocol this server does not offer (parameters, time, assets,
/// the connection graph): answered with an error status naming the capability.
struct UnsupportedOp {
  std::string op;
  std::string capability;
};

/// Longest list a client message may carry (subscriptions, ids, channels).
inline constexpr std::size_t kMaxItemsPerMessage = 1024;

using ClientMessage = std::variant<Subscribe, Unsubscribe, ClientAdvertise, ClientUnadvertise, ClientMessageData,
                                   ServiceCallRequest, UnsupportedOp>;

/// A parsed client message, or what was wrong with it (`error` non-empty:
/// malformed JSON, a missing or mistyped field, an unknown op or opcode, a
/// binary message cut short).
struct Parsed {
  ClientMessage message;
  std::string error;
  bool ok() const { return error.empty(); }
};
Parsed parseClientText(std::string_view text);
Parsed parseClientBinary(std::string_view bytes);

}  // namespace inspect::server::foxglove
