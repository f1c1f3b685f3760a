#pragma once
// A real MQTT broker for a test (Debian's mosquitto 2.0): on 127.0.0.1 and a
// port the kernel chose, with its own password file (user `scada`) and no
// anonymous clients, no persistence; killed and started again on the same
// port for an outage. docs/sparkplug.md, tests of pc_server/sparkplug.
#include <cstdint>
#include <string>

#include "tests/support/process.hpp"

namespace inspect::test {

/// TLS on the broker's listener: its CA, certificate and key; clients must
/// show a certificate of that CA too (and still log in with the password).
struct BrokerTls {
  std::string ca, cert, key;
};

class MosquittoBroker {
 public:
  /// Starts it with its files in `dir`; throws std::runtime_error when it does not listen within 5 s.
  explicit MosquittoBroker(const std::string& dir, const BrokerTls& tls = {});
  ~MosquittoBroker();
  uint16_t port() const { return port_; }
  /// A credentials file for clients (`username:` / `password:`, mode 0600).
  const std::string& credentialsFile() const { return credentials_; }
  /// SIGKILL: the broker is gone at once, as in a crash.
  void kill();
  /// Starts it again on the same port.
  void start();

 private:
  std::string dir_, conf_, credentials_;
  uint16_t port_ = 0;
  Process proc_;
};

}  // namespace inspect::test
