#include "pc_server/sparkplug/mqtt_session.hpp"

#include <mosquitto.h>

#include <cerrno>
#include <cstring>
#include <mutex>

namespace inspect::server::sparkplug {

namespace {
void libInit() {
  static std::once_flag once;
  std::call_once(once, [] { mosquitto_lib_init(); });
}
}  // namespace

std::string MqttSession::errorText(int rc) { return mosquitto_strerror(rc); }

MqttSession::MqttSession(const MqttOptions& o, Callbacks cb) : cb_(std::move(cb)), opts_(o) {
  libInit();
  mosq_ = mosquitto_new(o.client_id.c_str(), /*clean_session=*/true, this);
  if (!mosq_) {
    lost_ = true;
    error_ = "mosquitto_new failed";
    return;
  }
  mosquitto_connect_callback_set(mosq_, [](struct mosquitto*, void* self, int rc) {
    auto* s = static_cast<MqttSession*>(self);
    if (rc != 0) {
      s->lost_ = true;
      s->error_ = std::string("the broker refused the connection: ") + mosquitto_connack_string(rc);
    } else {
      s->connected_ = true;
    }
    if (s->cb_.connected) s->cb_.connected(rc);
  });
  mosquitto_disconnect_callback_set(mosq_, [](struct mosquitto*, void* self, int rc) {
    auto* s = static_cast<MqttSession*>(self);
    s->lost_ = true;
    if (s->error_.empty()) s->error_ = rc == 0 ? "disconnected" : s->lostText(rc);
  });
  mosquitto_publish_callback_set(mosq_, [](struct mosquitto*, void* self, int mid) {
    auto* s = static_cast<MqttSession*>(self);
    if (s->cb_.delivered) s->cb_.delivered(mid);
  });
  mosquitto_message_callback_set(mosq_, [](struct mosquitto*, void* self, const struct mosquitto_message* m) {
    auto* s = static_cast<MqttSession*>(self);
    if (s->cb_.message && m && m->topic)
      s->cb_.message(m->topic, std::string(static_cast<const char*>(m->payload), static_cast<std::size_t>(m->payloadlen)));
  });
}

MqttSession::~MqttSession() {
  if (mosq_) mosquitto_destroy(mosq_);
}

std::string MqttSession::connect(const std::string& will_topic, const std::string& will_payload) {
  if (!mosq_) return error_;
  int rc = MOSQ_ERR_SUCCESS;
  if (!opts_.username.empty())
    rc = mosquitto_username_pw_set(mosq_, opts_.username.c_str(), opts_.password.empty() ? nullptr : opts_.password.c_str());
  if (rc == MOSQ_ERR_SUCCESS && !opts_.ca.empty())
    rc = mosquitto_tls_set(mosq_, opts_.ca.c_str(), nullptr, opts_.cert.empty() ? nullptr : opts_.cert.c_str(),
                           opts_.key.empty() ? nullptr : opts_.key.c_str(), nullptr);
  if (rc == MOSQ_ERR_SUCCESS)
    rc = mosquitto_will_set(mosq_, will_topic.c_str(), static_cast<int>(will_payload.size()), will_payload.data(), 1, false);
  if (rc == MOSQ_ERR_SUCCESS) mosquitto_int_option(mosq_, MOSQ_OPT_TCP_NODELAY, 1);
  // Not blocking: a broker whose host drops the SYN would hold this thread
  // (and stop()) for the kernel's connect timeout, about 2 minutes; step()
  // finishes the connection, and the owner gives up on a CONNACK that is late.
  if (rc == MOSQ_ERR_SUCCESS) rc = mosquitto_connect_async(mosq_, opts_.host.c_str(), opts_.port, opts_.keepalive_s);
  if (rc != MOSQ_ERR_SUCCESS) {
    lost_ = true;
    error_ = lostText(rc);
    return error_;
  }
  return "";
}

std::string MqttSession::noAnswerText() const {
  return "no answer (CONNACK) from " + opts_.host + ":" + std::to_string(opts_.port) + " within " +
         std::to_string(opts_.keepalive_s) + " s (keepalive_s)";
}

std::string MqttSession::lostText(int rc) const {
  if (!connected_ && rc == MOSQ_ERR_KEEPALIVE) return noAnswerText();  // libmosquitto's own text is "Unknown error."
  const std::string why = rc == MOSQ_ERR_ERRNO ? std::string(std::strerror(errno)) : errorText(rc);
  return connected_ ? "connection lost: " + why
                    : "cannot connect to " + opts_.host + ":" + std::to_string(opts_.port) + ": " + why;
}

bool MqttSession::step(int timeout_ms) {
  if (!mosq_ || lost_) return false;
  const int rc = mosquitto_loop(mosq_, timeout_ms, 1);
  if (rc != MOSQ_ERR_SUCCESS && !lost_) {
    lost_ = true;
    error_ = lostText(rc);
  }
  return !lost_;
}

int MqttSession::publish(const std::string& topic, const std::string& payload, int qos) {
  if (!mosq_ || lost_) return -1;
  int mid = 0;
  const int rc = mosquitto_publish(mosq_, &mid, topic.c_str(), static_cast<int>(payload.size()), payload.data(), qos, false);
  if (rc != MOSQ_ERR_SUCCESS) {
    lost_ = true;
    error_ = "publish: " + errorText(rc);
    return -1;
  }
  return mid;
}

bool MqttSession::subscribe(const std::string& pattern, int qos) {
  return mosq_ && !lost_ && mosquitto_subscribe(mosq_, nullptr, pattern.c_str(), qos) == MOSQ_ERR_SUCCESS;
}

void MqttSession::disconnect() {
  // Until the DISCONNECT is out (the disconnect callback): a socket closed
  // before it makes the broker publish the Will as well (at most 1 s).
  if (mosq_ && !lost_ && mosquitto_disconnect(mosq_) == MOSQ_ERR_SUCCESS) {
    for (int i = 0; i < 40 && !lost_; ++i) mosquitto_loop(mosq_, 50, 1);
    if (!lost_) error_ = "the DISCONNECT was not out within 2 s: the broker may publish the Will too";
  }
  lost_ = true;
}

}  // namespace inspect::server::sparkplug
