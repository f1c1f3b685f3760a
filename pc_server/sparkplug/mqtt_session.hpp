#pragma once
// One MQTT session to the broker through libmosquitto (Debian's
// libmosquitto1, MQTT 3.1.1): connect with a Will, publish, subscribe, and
// what came back (CONNACK, PUBACKs, messages, the connection lost), all on
// the one thread that calls step(). A lost session is not reconnected here:
// the owner makes a new one (a new Will, nothing of the old in flight).
#include <cstdint>
#include <functional>
#include <string>

struct mosquitto;

namespace inspect::server::sparkplug {

struct MqttOptions {
  std::string client_id;
  std::string host;
  uint16_t port = 1883;
  int keepalive_s = 10;
  std::string username, password;  // "" = none
  std::string ca, cert, key;       // TLS when ca is set
};

class MqttSession {
 public:
  struct Callbacks {
    std::function<void(int rc)> connected;            // CONNACK: rc 0 = accepted
    std::function<void(int mid)> delivered;           // the broker has message mid (PUBACK; QoS 0: sent)
    std::function<void(const std::string& topic, const std::string& payload)> message;
  };
  MqttSession(const MqttOptions& o, Callbacks cb);
  ~MqttSession();
  MqttSession(const MqttSession&) = delete;
  MqttSession& operator=(const MqttSession&) = delete;

  /// Starts connecting with the Will (QoS 1, not retained), without
  /// blocking: step() completes it; "" or why not.
  std::string connect(const std::string& will_topic, const std::string& will_payload);
  /// Runs the network for up to `timeout_ms`: callbacks fire here. False once the session is lost.
  bool step(int timeout_ms);
  /// Publishes; the message id (for `delivered`), or -1 (the session is lost).
  int publish(const std::string& topic, const std::string& payload, int qos);
  bool subscribe(const std::string& pattern, int qos);
  /// Disconnects cleanly (the broker then drops the Will).
  void disconnect();
  bool lost() const { return lost_; }
  /// The broker accepted the session (CONNACK 0).
  bool connected() const { return connected_; }
  /// "no answer (CONNACK) from host:port within N s (keepalive_s)": a
  /// broker that never answered; the owner gives up after the keep-alive.
  std::string noAnswerText() const;
  const std::string& error() const { return error_; }

  /// libmosquitto's text of an error number.
  static std::string errorText(int rc);

 private:
  struct mosquitto* mosq_ = nullptr;
  Callbacks cb_;
  MqttOptions opts_;
  bool lost_ = false;
  bool connected_ = false;
  std::string error_;
  /// Why the session ended with libmosquitto's `rc`: "cannot connect to
  /// host:port: ..." before the CONNACK, "connection lost: ..." after.
  std::string lostText(int rc) const;
};

}  // namespace inspect::server::sparkplug
