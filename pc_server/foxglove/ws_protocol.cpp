#include "pc_server/foxglove/ws_protocol.hpp"

#include <cstring>
#include <limits>

#include <nlohmann/json.hpp>

namespace inspect::server::foxglove {

using Json = nlohmann::json;

namespace {

void putU32(std::string& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out += static_cast<char>((v >> (8 * i)) & 0xFF);
}
void putU64(std::string& out, uint64_t v) {
  for (int i = 0; i < 8; ++i) out += static_cast<char>((v >> (8 * i)) & 0xFF);
}
uint32_t getU32(std::string_view b, std::size_t at) {
  uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<uint32_t>(static_cast<unsigned char>(b[at + i])) << (8 * i);
  return v;
}

/// A thrown parse problem: the text names the field and what was wrong.
struct Bad {
  std::string what;
};

const Json& field(const Json& obj, const char* name, const std::string& where) {
  const auto it = obj.find(name);
  if (it == obj.end()) throw Bad{where + ": missing \"" + name + "\""};
  return *it;
}
uint32_t idOf(const Json& v, const std::string& what) {
  if (!v.is_number_integer() && !v.is_number_unsigned()) throw Bad{what + " must be an integer"};
  if (v.is_number_unsigned()) {
    const auto u = v.get<uint64_t>();
    if (u > std::numeric_limits<uint32_t>::max()) throw Bad{what + " " + std::to_string(u) + " is not a uint32"};
    return static_cast<uint32_t>(u);
  }
  const auto i = v.get<int64_t>();
  if (i < 0 || i > static_cast<int64_t>(std::numeric_limits<uint32_t>::max()))
    throw Bad{what + " " + std::to_string(i) + " is not a uint32"};
  return static_cast<uint32_t>(i);
}
const Json& arrayField(const Json& obj, const char* name, const std::string& op) {
  const Json& a = field(obj, name, op);
  if (!a.is_array()) throw Bad{op + ": \"" + name + "\" must be an array"};
  if (a.size() > kMaxItemsPerMessage)
    throw Bad{op + ": \"" + name + "\" has " + std::to_string(a.size()) + " items, at most " +
              std::to_string(kMaxItemsPerMessage)};
  return a;
}
std::string stringField(const Json& obj, const char* name, const std::string& where) {
  const Json& s = field(obj, name, where);
  if (!s.is_string()) throw Bad{where + ": \"" + name + "\" must be a string"};
  return s.get<std::string>();
}
std::vector<uint32_t> idList(const Json& obj, const char* name, const std::string& op) {
  std::vector<uint32_t> ids;
  const Json& a = arrayField(obj, name, op);
  ids.reserve(a.size());
  for (std::size_t i = 0; i < a.size(); ++i)
    ids.push_back(idOf(a[i], op + ": " + name + "[" + std::to_string(i) + "]"));
  return ids;
}

ClientMessage parseOp(const Json& j) {
  if (!j.is_object()) throw Bad{"a text message must be a JSON object"};
  const auto op_it = j.find("op");
  if (op_it == j.end() || !op_it->is_string()) throw Bad{"a text message needs a string \"op\""};
  const std::string op = op_it->get<std::string>();
  if (op == "subscribe") {
    Subscribe s;
    const Json& a = arrayField(j, "subscriptions", op);
    for (std::size_t i = 0; i < a.size(); ++i) {
      const std::string where = "subscribe: subscriptions[" + std::to_string(i) + "]";
      if (!a[i].is_object()) throw Bad{where + " must be an object"};
      s.subscriptions.push_back(
          {idOf(field(a[i], "id", where), where + ".id"), idOf(field(a[i], "channelId", where), where + ".channelId")});
    }
    return s;
  }
  if (op == "unsubscribe") return Unsubscribe{idList(j, "subscriptionIds", op)};
  if (op == "advertise") {
    ClientAdvertise adv;
    const Json& a = arrayField(j, "channels", op);
    for (std::size_t i = 0; i < a.size(); ++i) {
      const std::string where = "advertise: channels[" + std::to_string(i) + "]";
      if (!a[i].is_object()) throw Bad{where + " must be an object"};
      ClientChannel c;
      c.id = idOf(field(a[i], "id", where), where + ".id");
      c.topic = stringField(a[i], "topic", where);
      c.encoding = stringField(a[i], "encoding", where);
      c.schema_name = stringField(a[i], "schemaName", where);
      adv.channels.push_back(std::move(c));
    }
    return adv;
  }
  if (op == "unadvertise") return ClientUnadvertise{idList(j, "channelIds", op)};
  if (op == "getParameters" || op == "setParameters") return UnsupportedOp{op, "parameters"};
  if (op == "subscribeParameterUpdates" || op == "unsubscribeParameterUpdates")
    return UnsupportedOp{op, "parametersSubscribe"};
  if (op == "subscribeConnectionGraph" || op == "unsubscribeConnectionGraph") return UnsupportedOp{op, "connectionGraph"};
  if (op == "fetchAsset") return UnsupportedOp{op, "assets"};
  throw Bad{"unknown op \"" + op.substr(0, 64) + "\""};
}

}  // namespace

std::string chooseSubprotocol(std::string_view offered) {
  bool sdk = false;
  std::size_t i = 0;
  while (i <= offered.size()) {
    std::size_t j = offered.find(',', i);
    if (j == std::string_view::npos) j = offered.size();
    std::string_view tok = offered.substr(i, j - i);
    while (!tok.empty() && (tok.front() == ' ' || tok.front() == '\t')) tok.remove_prefix(1);
    while (!tok.empty() && (tok.back() == ' ' || tok.back() == '\t')) tok.remove_suffix(1);
    if (tok == kSubprotocol) return std::string(kSubprotocol);
    if (tok == kSubprotocolSdk) sdk = true;
    i = j + 1;
  }
  return sdk ? std::string(kSubprotocolSdk) : std::string();
}

std::string serverInfoJson(const std::string& name, const std::vector<std::string>& capabilities,
                           const std::vector<std::string>& supported_encodings, const std::string& session_id,
                           const std::map<std::string, std::string>& metadata) {
  Json j{{"op", "serverInfo"}, {"name", name}, {"capabilities", capabilities}, {"sessionId", session_id}};
  if (!supported_encodings.empty()) j["supportedEncodings"] = supported_encodings;
  j["metadata"] = Json::object();
  for (const auto& [k, v] : metadata) j["metadata"][k] = v;
  return j.dump();
}

std::string advertiseJson(const std::vector<Channel>& channels) {
  Json list = Json::array();
  for (const auto& c : channels) {
    Json ch{{"id", c.id}, {"topic", c.topic}, {"encoding", c.encoding}, {"schemaName", c.schema_name},
            {"schema", c.schema}};
    if (!c.schema_encoding.empty()) ch["schemaEncoding"] = c.schema_encoding;
    list.push_back(std::move(ch));
  }
  return Json{{"op", "advertise"}, {"channels", std::move(list)}}.dump();
}

std::string unadvertiseJson(const std::vector<uint32_t>& ids) {
  return Json{{"op", "unadvertise"}, {"channelIds", ids}}.dump();
}

std::string advertiseServicesJson(const std::vector<Service>& services) {
  Json list = Json::array();
  for (const auto& s : services) {
    const auto schema = [](const std::string& name, const std::string& text) {
      return Json{{"encoding", "json"}, {"schemaName", name}, {"schemaEncoding", "jsonschema"}, {"schema", text}};
    };
    list.push_back(Json{{"id", s.id},
                        {"name", s.name},
                        {"type", s.type},
                        {"request", schema(s.type + "_Request", s.request_schema)},
                        {"response", schema(s.type + "_Response", s.response_schema)}});
  }
  return Json{{"op", "advertiseServices"}, {"services", std::move(list)}}.dump();
}

std::string statusJson(StatusLevel level, const std::string& message, const std::string& id) {
  Json j{{"op", "status"}, {"level", static_cast<int>(level)}, {"message", message}};
  if (!id.empty()) j["id"] = id;
  // Text from a client (an op name, a topic) may be cut mid-character: replace, never throw.
  return j.dump(-1, ' ', false, Json::error_handler_t::replace);
}

std::string serviceCallFailureJson(uint32_t service_id, uint32_t call_id, const std::string& message) {
  return Json{{"op", "serviceCallFailure"}, {"serviceId", service_id}, {"callId", call_id}, {"message", message}}.dump(
      -1, ' ', false, Json::error_handler_t::replace);
}

std::string messageDataHeader(uint32_t subscription_id, uint64_t timestamp_ns) {
  std::string h;
  h.reserve(kMessageDataHeaderBytes);
  h += '\x01';
  putU32(h, subscription_id);
  putU64(h, timestamp_ns);
  return h;
}

std::string serviceCallResponse(uint32_t service_id, uint32_t call_id, std::string_view encoding,
                                std::string_view payload) {
  std::string out;
  out.reserve(13 + encoding.size() + payload.size());
  out += '\x03';
  putU32(out, service_id);
  putU32(out, call_id);
  putU32(out, static_cast<uint32_t>(encoding.size()));
  out.append(encoding);
  out.append(payload);
  return out;
}

Parsed parseClientText(std::string_view text) {
  Parsed p;
  Json j = Json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) {
    p.error = "malformed JSON";
    return p;
  }
  try {
    p.message = parseOp(j);
  } catch (const Bad& b) {
    p.error = b.what;
  } catch (const std::exception& e) {  // nlohmann type errors the checks above did not foresee
    p.error = std::string("bad message: ") + e.what();
  }
  return p;
}

Parsed parseClientBinary(std::string_view b) {
  Parsed p;
  if (b.empty()) {
    p.error = "empty binary message";
    return p;
  }
  const auto op = static_cast<unsigned char>(b[0]);
  if (op == 0x01) {
    if (b.size() < 5) {
      p.error = "client message data: " + std::to_string(b.size()) + " bytes, needs at least 5 (opcode, channel id)";
      return p;
    }
    p.message = ClientMessageData{getU32(b, 1), b.substr(5)};
    return p;
  }
  if (op == 0x02) {
    if (b.size() < 13) {
      p.error = "service call request: " + std::to_string(b.size()) +
                " bytes, needs at least 13 (opcode, service id, call id, encoding length)";
      return p;
    }
    const uint32_t enc_len = getU32(b, 9);
    if (enc_len > b.size() - 13) {
      p.error = "service call request: encoding length " + std::to_string(enc_len) + " runs past the message (" +
                std::to_string(b.size()) + " bytes)";
      return p;
    }
    p.message = ServiceCallRequest{getU32(b, 1), getU32(b, 5), std::string(b.substr(13, enc_len)), b.substr(13 + enc_len)};
    return p;
  }
  p.error = "unknown binary opcode 0x" + std::string(1, "0123456789abcdef"[op >> 4]) + "0123456789abcdef"[op & 15];
  return p;
}

}  // namespace inspect::server::foxglove
