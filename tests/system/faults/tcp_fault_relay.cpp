// tcp_fault_relay: a TCP relay between robot_client and pc_server that can
// stop one direction of the link on command, for fault injection. Bytes pass
// through untouched (TLS records included). A stalled direction is neither
// read nor written: the data waits in the relay and the kernels' buffers, as
// on a network path that stopped delivering, and flows on when released.
// When either side closes or fails, both sides of that connection are closed.
// For tests only (tests/system/faults, docs/failsafes.md).
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "shared/util/cli_args.hpp"
#include "shared/util/clock.hpp"

namespace {

volatile std::sig_atomic_t g_stop = 0;

constexpr const char* kUsage = R"(usage: tcp_fault_relay --target HOST:PORT --control FIFO [options]

Accepts TCP connections (robot_client) and relays each to --target (pc_server).

options:
  --listen ADDR:PORT  where to listen (default 127.0.0.1:0, any free port)
  --port-file FILE    write the port listened on to FILE once listening
  --control FIFO      read commands from FIFO (made if missing), one per line:
                        stall up     robot -> server stops (telemetry, heartbeats, acks)
                        stall down   server -> robot stops (commands, heartbeats)
                        stall both
                        cut          the link goes down: every connection is closed
                                     (bytes in flight lost) and new ones are refused
                                     (accepted and closed) until `flow`
                        flow         both directions flow again (and connections are taken)
                      each applied command is printed: "tcp_fault_relay: <command> at mono_ns=<ns>"
  --help
)";

[[noreturn]] void die(const std::string& msg) {
  std::fprintf(stderr, "tcp_fault_relay: %s\n", msg.c_str());
  std::exit(2);
}

void say(const std::string& msg) {
  std::printf("tcp_fault_relay: %s at mono_ns=%lld\n", msg.c_str(), static_cast<long long>(inspect::monoNowNs()));
  std::fflush(stdout);
}

sockaddr_in parseAddr(const std::string& s, const std::string& flag) {
  const auto colon = s.rfind(':');
  if (colon == std::string::npos) die(flag + ": '" + s + "' must be ADDR:PORT");
  sockaddr_in a{};
  a.sin_family = AF_INET;
  const std::string host = s.substr(0, colon) == "localhost" ? "127.0.0.1" : s.substr(0, colon);
  if (::inet_pton(AF_INET, host.c_str(), &a.sin_addr) != 1) die(flag + ": '" + host + "' is not an IPv4 address");
  const long port = std::strtol(s.c_str() + colon + 1, nullptr, 10);
  if (port < 0 || port > 65535) die(flag + ": bad port in '" + s + "'");
  a.sin_port = htons(static_cast<uint16_t>(port));
  return a;
}

void nonBlocking(int fd) { ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK); }

// One relayed connection: robot side `a`, server side `b`.
struct Conn {
  int a = -1, b = -1;
  std::string up, down;  // bytes read and not yet written: a -> b, b -> a
  bool closing = false;
  ~Conn() {
    if (a >= 0) ::close(a);
    if (b >= 0) ::close(b);
  }
};

constexpr std::size_t kMaxPending = 256 * 1024;

// Reads from `from` into `buf`; false on EOF or error.
bool pull(int from, std::string& buf) {
  char tmp[16384];
  while (buf.size() < kMaxPending) {
    const ssize_t n = ::read(from, tmp, sizeof tmp);
    if (n > 0) {
      buf.append(tmp, static_cast<std::size_t>(n));
      continue;
    }
    if (n == 0) return false;
    return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR;
  }
  return true;
}

// Writes what `to` accepts now; false on error.
bool push(int to, std::string& buf) {
  while (!buf.empty()) {
    const ssize_t n = ::send(to, buf.data(), buf.size(), MSG_NOSIGNAL);
    if (n > 0) {
      buf.erase(0, static_cast<std::size_t>(n));
      continue;
    }
    return n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR);
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::string listen_s = "127.0.0.1:0", target_s, port_file, control_path;
  inspect::cli::readOrExit("tcp_fault_relay", argc, argv, [&](inspect::cli::ArgReader& a) {
    if (a.isHelp()) {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else if (a.is("--listen")) {
      listen_s = a.path();
    } else if (a.is("--target")) {
      target_s = a.path();
    } else if (a.is("--port-file")) {
      port_file = a.path();
    } else if (a.is("--control")) {
      control_path = a.path();
    } else {
      a.unknown();
    }
  });
  if (target_s.empty() || control_path.empty()) die("--target and --control are required");
  const sockaddr_in target = parseAddr(target_s, "--target");
  const sockaddr_in local = parseAddr(listen_s, "--listen");

  std::signal(SIGINT, [](int) { g_stop = 1; });
  std::signal(SIGTERM, [](int) { g_stop = 1; });
  std::signal(SIGPIPE, SIG_IGN);

  const int lfd = ::socket(AF_INET, SOCK_STREAM, 0);
  const int one = 1;
  ::setsockopt(lfd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (::bind(lfd, reinterpret_cast<const sockaddr*>(&local), sizeof local) != 0)
    die("cannot bind " + listen_s + ": " + std::strerror(errno));
  if (::listen(lfd, 16) != 0) die(std::string("listen: ") + std::strerror(errno));
  nonBlocking(lfd);
  sockaddr_in bound{};
  socklen_t blen = sizeof bound;
  ::getsockname(lfd, reinterpret_cast<sockaddr*>(&bound), &blen);
  const int port = ntohs(bound.sin_port);

  if (::mkfifo(control_path.c_str(), 0600) != 0 && errno != EEXIST)
    die("--control: cannot make " + control_path + ": " + std::strerror(errno));
  const int control = ::open(control_path.c_str(), O_RDWR | O_NONBLOCK);  // never EOF
  if (control < 0) die("--control: cannot open " + control_path + ": " + std::strerror(errno));

  std::printf("tcp_fault_relay: listening on port %d, relaying to %s\n", port, target_s.c_str());
  std::fflush(stdout);
  if (!port_file.empty()) {
    const std::string tmp = port_file + ".tmp";
    std::ofstream(tmp) << port << "\n";
    std::rename(tmp.c_str(), port_file.c_str());
  }

  bool stall_up = false, stall_down = false, cut = false;
  std::string control_buf;
  std::vector<std::unique_ptr<Conn>> conns;
  uint64_t accepted = 0;
  while (!g_stop) {
    std::vector<pollfd> fds;
    fds.push_back({lfd, POLLIN, 0});
    fds.push_back({control, POLLIN, 0});
    for (const auto& c : conns) {
      short ea = 0, eb = 0;
      if (!stall_up && c->up.size() < kMaxPending) ea |= POLLIN;
      if (!stall_down && !c->down.empty()) ea |= POLLOUT;
      if (!stall_down && c->down.size() < kMaxPending) eb |= POLLIN;
      if (!stall_up && !c->up.empty()) eb |= POLLOUT;
      fds.push_back({c->a, ea, 0});
      fds.push_back({c->b, eb, 0});
    }
    const int r = ::poll(fds.data(), fds.size(), 50);
    if (r < 0 && errno != EINTR) die(std::string("poll: ") + std::strerror(errno));
    if (fds[1].revents & POLLIN) {
      char buf[256];
      for (;;) {
        const ssize_t n = ::read(control, buf, sizeof buf);
        if (n <= 0) break;
        control_buf.append(buf, static_cast<std::size_t>(n));
      }
      for (auto nl = control_buf.find('\n'); nl != std::string::npos; nl = control_buf.find('\n')) {
        std::string cmd = control_buf.substr(0, nl);
        control_buf.erase(0, nl + 1);
        while (!cmd.empty() && (cmd.back() == '\r' || cmd.back() == ' ')) cmd.pop_back();
        if (cmd == "stall up") stall_up = true;
        else if (cmd == "stall down") stall_down = true;
        else if (cmd == "stall both") stall_up = stall_down = true;
        else if (cmd == "flow") stall_up = stall_down = cut = false;
        else if (cmd == "cut") {
          cut = true;
          for (auto& c : conns) c->closing = true;  // closed below, their bytes dropped
        }
        else {
          std::fprintf(stderr, "tcp_fault_relay: unknown control command '%s'\n", cmd.c_str());
          continue;
        }
        say(cmd);
      }
    }
    // Move data (only where poll said so; a stalled direction is not touched).
    for (std::size_t i = 0; i < conns.size(); ++i) {
      Conn& c = *conns[i];
      if (c.closing) continue;  // cut
      const short ra = fds[2 + 2 * i].revents, rb = fds[3 + 2 * i].revents;
      bool ok = true;
      if (!stall_up && (ra & (POLLIN | POLLHUP | POLLERR))) ok = pull(c.a, c.up) && ok;
      if (!stall_down && (rb & (POLLIN | POLLHUP | POLLERR))) ok = pull(c.b, c.down) && ok;
      if (!stall_up) ok = push(c.b, c.up) && ok;
      if (!stall_down) ok = push(c.a, c.down) && ok;
      if (!ok) {
        // One side closed or failed: pass on what the other direction still has, then close both.
        if (!stall_down) push(c.a, c.down);
        if (!stall_up) push(c.b, c.up);
        c.closing = true;
      }
    }
    for (auto it = conns.begin(); it != conns.end();) {
      if ((*it)->closing) {
        say("connection closed");
        it = conns.erase(it);
      } else {
        ++it;
      }
    }
    if (fds[0].revents & POLLIN) {
      for (;;) {
        const int a = ::accept(lfd, nullptr, nullptr);
        if (a < 0) break;
        if (cut) {  // the link is down: nothing gets through
          ::close(a);
          say("connection refused (cut)");
          continue;
        }
        const int b = ::socket(AF_INET, SOCK_STREAM, 0);
        if (::connect(b, reinterpret_cast<const sockaddr*>(&target), sizeof target) != 0) {
          std::fprintf(stderr, "tcp_fault_relay: cannot connect to %s: %s\n", target_s.c_str(), std::strerror(errno));
          ::close(a);
          ::close(b);
          continue;
        }
        ::setsockopt(a, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        ::setsockopt(b, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        nonBlocking(a);
        nonBlocking(b);
        auto c = std::make_unique<Conn>();
        c->a = a;
        c->b = b;
        conns.push_back(std::move(c));
        ++accepted;
        say("connection " + std::to_string(accepted) + " accepted");
      }
    }
  }
  std::printf("tcp_fault_relay: %llu connections relayed\n", static_cast<unsigned long long>(accepted));
  ::close(control);
  ::close(lfd);
  return 0;
}
