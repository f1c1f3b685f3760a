#include "tests/support/mosquitto_broker.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <pwd.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <stdexcept>
#include <thread>

namespace inspect::test {

namespace {
// A port the kernel chose on 127.0.0.1 (closed again for the broker to take).
uint16_t ephemeralPort() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  if (fd < 0 || ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) != 0)
    throw std::runtime_error("no ephemeral port on 127.0.0.1");
  ::close(fd);
  return ntohs(a.sin_port);
}

bool listening(uint16_t port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool ok = fd >= 0 && ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  if (fd >= 0) ::close(fd);
  return ok;
}
}  // namespace

MosquittoBroker::MosquittoBroker(const std::string& dir, const BrokerTls& tls) : dir_(dir) {
  const std::string pwfile = dir_ + "/mosquitto.passwd";
  if (std::system(("mosquitto_passwd -b -c '" + pwfile + "' scada 'sc4da-test' >/dev/null 2>&1").c_str()) != 0)
    throw std::runtime_error("mosquitto_passwd failed (Debian package mosquitto; scripts/setup.sh)");
  ::chmod(pwfile.c_str(), 0600);
  credentials_ = dir_ + "/scada-credentials.yaml";
  writeFile(credentials_, "username: scada\npassword: sc4da-test\n");
  ::chmod(credentials_.c_str(), 0600);
  port_ = ephemeralPort();
  conf_ = dir_ + "/mosquitto.conf";
  // Run as whoever runs the test (as root, mosquitto would become user
  // mosquitto, who cannot read the test's directory).
  const passwd* pw = ::getpwuid(::getuid());
  writeFile(conf_, "listener " + std::to_string(port_) + " 127.0.0.1\nallow_anonymous false\npassword_file " + pwfile +
                       "\npersistence false\nlog_dest stderr\nuser " + (pw ? pw->pw_name : "root") + "\n" +
                       (tls.ca.empty() ? std::string()
                                       : "cafile " + tls.ca + "\ncertfile " + tls.cert + "\nkeyfile " + tls.key +
                                             "\nrequire_certificate true\ntls_version tlsv1.2\n"));
  start();
}

MosquittoBroker::~MosquittoBroker() { kill(); }

void MosquittoBroker::kill() {
  if (proc_.pid() > 0 && proc_.running()) {
    proc_.signal(SIGKILL);
    proc_.wait(5.0);
  }
}

void MosquittoBroker::start() {
  proc_ = Process::spawn({"/usr/sbin/mosquitto", "-c", conf_}, dir_ + "/mosquitto.out", dir_ + "/mosquitto.out");
  for (int i = 0; i < 250; ++i) {  // 5 s
    if (listening(port_)) return;
    if (!proc_.running()) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  throw std::runtime_error("mosquitto did not listen on 127.0.0.1:" + std::to_string(port_) + ": " +
                           readFile(dir_ + "/mosquitto.out"));
}

}  // namespace inspect::test
