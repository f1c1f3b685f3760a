// serial_relay: sits on the serial line between mcu_sim and robot_client and
// damages it on purpose: random bit errors at a given bit error rate and
// bursts of random garbage bytes, in either direction, and cuts one or both
// directions on command (--control). For tests only.
#include <fcntl.h>
#include <poll.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <array>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "shared/util/cli_args.hpp"
#include "shared/util/clock.hpp"
#include "shared/util/realtime.hpp"
#include "sim/mcu_sim/pty_port.hpp"

namespace {

volatile std::sig_atomic_t g_stop = 0;

constexpr const char* kUsage = R"(usage: serial_relay --mcu PATH --pty-link PATH [options]

Relays bytes between the MCU's serial device (PATH, e.g. mcu_sim's pty) and a
new pseudo-terminal (linked at --pty-link) for robot_client, injecting errors.

options:
  --ber-up X          bit error rate towards the MCU (default 0)
  --ber-down X        bit error rate towards robot_client (default 0)
  --garbage-per-s N   bursts of 1-24 random bytes per second, each direction (default 0)
  --seed N            random seed (default 1)
  --realtime-priority N  relay SCHED_FIFO at priority N in [0, 99] once started (a wire stand-in:
                      above robot_client's loop, e.g. 20); 0 = normal (default)
  --control FIFO      read commands from FIFO (made if missing), one per line:
                        stall up|down|both   cut that direction: bytes read from it are dropped
                        flow                 both directions pass again
                      each applied command is printed: "serial_relay: <command> at mono_ns=<ns>"
  --help
)";

struct Direction {
  const char* name;
  int idx;  // 0 = down (to robot_client), 1 = up (to the MCU)
  double ber = 0.0;
  bool stalled = false;
  uint64_t bytes = 0, flipped_bits = 0, garbage_bytes = 0, dropped = 0, cut = 0;
};

class Damage {
 public:
  explicit Damage(unsigned seed) : rng_(seed) {}
  // Flips bits with probability `ber` each (geometric skipping keeps it cheap).
  void corrupt(std::vector<uint8_t>& buf, Direction& d) {
    d.bytes += buf.size();
    if (d.ber <= 0.0) return;
    std::geometric_distribution<uint64_t> gap(d.ber);
    const uint64_t bits = buf.size() * 8;
    uint64_t pos = carry_[d.idx];
    while (pos < bits) {
      buf[pos / 8] ^= static_cast<uint8_t>(1u << (pos % 8));
      ++d.flipped_bits;
      pos += 1 + gap(rng_);
    }
    carry_[d.idx] = pos - bits;
  }
  void garbage(std::vector<uint8_t>& buf, Direction& d) {
    std::uniform_int_distribution<int> len(1, 24), byte(0, 255);
    const int n = len(rng_);
    for (int i = 0; i < n; ++i) buf.push_back(static_cast<uint8_t>(byte(rng_)));
    d.garbage_bytes += static_cast<uint64_t>(n);
  }
  bool chance(double p) { return std::uniform_real_distribution<double>(0, 1)(rng_) < p; }
  void seedCarry(double ber_up, double ber_down) {
    if (ber_down > 0) carry_[0] = std::geometric_distribution<uint64_t>(ber_down)(rng_);
    if (ber_up > 0) carry_[1] = std::geometric_distribution<uint64_t>(ber_up)(rng_);
  }

 private:
  std::mt19937_64 rng_;
  uint64_t carry_[2] = {0, 0};
};

[[noreturn]] void die(const std::string& msg) {
  std::fprintf(stderr, "serial_relay: %s\n", msg.c_str());
  std::exit(2);
}

// Applies the complete lines of `buf` (commands from --control); keeps a partial last line.
void controlCommands(std::string& buf, Direction& up, Direction& down) {
  for (auto nl = buf.find('\n'); nl != std::string::npos; nl = buf.find('\n')) {
    std::string cmd = buf.substr(0, nl);
    buf.erase(0, nl + 1);
    while (!cmd.empty() && (cmd.back() == '\r' || cmd.back() == ' ')) cmd.pop_back();
    if (cmd == "stall up") {
      up.stalled = true;
    } else if (cmd == "stall down") {
      down.stalled = true;
    } else if (cmd == "stall both") {
      up.stalled = down.stalled = true;
    } else if (cmd == "flow") {
      up.stalled = down.stalled = false;
    } else {
      std::fprintf(stderr, "serial_relay: unknown control command '%s'\n", cmd.c_str());
      continue;
    }
    std::printf("serial_relay: %s at mono_ns=%lld\n", cmd.c_str(), static_cast<long long>(inspect::monoNowNs()));
    std::fflush(stdout);
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::string mcu_path, link_path, control_path;
  Direction up{"up", 1}, down{"down", 0};
  double garbage_per_s = 0;
  unsigned seed = 1;
  int realtime_priority = 0;
  inspect::cli::readOrExit("serial_relay", argc, argv, [&](inspect::cli::ArgReader& a) {
    if (a.isHelp()) {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else if (a.is("--mcu")) {
      mcu_path = a.path();
    } else if (a.is("--pty-link")) {
      link_path = a.path();
    } else if (a.is("--ber-up")) {
      up.ber = a.number(0, 0.5);
    } else if (a.is("--ber-down")) {
      down.ber = a.number(0, 0.5);
    } else if (a.is("--garbage-per-s")) {
      garbage_per_s = a.number(0);
    } else if (a.is("--control")) {
      control_path = a.path();
    } else if (a.is("--realtime-priority")) {
      realtime_priority = static_cast<int>(a.integer(0, 99));
    } else if (a.is("--seed")) {
      seed = static_cast<unsigned>(a.integer(0, 4294967295LL));
    } else {
      a.unknown();
    }
  });
  if (mcu_path.empty() || link_path.empty()) die("--mcu and --pty-link are required");

  const int mcu = ::open(mcu_path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
  if (mcu < 0) die("cannot open " + mcu_path + ": " + std::strerror(errno));
  termios tio{};
  if (::tcgetattr(mcu, &tio) == 0) {
    ::cfmakeraw(&tio);
    ::tcsetattr(mcu, TCSANOW, &tio);
  }
  inspect::sim::PtyPort host(link_path);
  std::printf("serial_relay: serial device %s\n", host.slavePath().c_str());
  std::fflush(stdout);

  int control = -1;
  if (!control_path.empty()) {
    if (::mkfifo(control_path.c_str(), 0600) != 0 && errno != EEXIST)
      die("--control: cannot make " + control_path + ": " + std::strerror(errno));
    // O_RDWR: the FIFO never reports end of file when a writer closes it.
    control = ::open(control_path.c_str(), O_RDWR | O_NONBLOCK);
    if (control < 0) die("--control: cannot open " + control_path + ": " + std::strerror(errno));
  }
  std::string control_buf;

  std::signal(SIGINT, [](int) { g_stop = 1; });
  std::signal(SIGTERM, [](int) { g_stop = 1; });

  if (const std::string why = inspect::util::enterRealtime(realtime_priority); !why.empty())
    std::fprintf(stderr, "serial_relay: warning: running at normal priority: %s\n", why.c_str());

  Damage dmg(seed);
  dmg.seedCarry(up.ber, down.ber);
  std::array<uint8_t, 4096> buf{};
  std::vector<uint8_t> chunk;
  const double poll_s = 0.005;
  while (!g_stop) {
    pollfd fds[3] = {{mcu, POLLIN, 0}, {host.fd(), POLLIN, 0}, {control, POLLIN, 0}};
    ::poll(fds, control >= 0 ? 3 : 2, static_cast<int>(poll_s * 1000));
    if (control >= 0 && (fds[2].revents & POLLIN)) {
      char cbuf[256];
      for (;;) {
        const ssize_t n = ::read(control, cbuf, sizeof cbuf);
        if (n <= 0) break;
        control_buf.append(cbuf, static_cast<std::size_t>(n));
      }
      controlCommands(control_buf, up, down);
    }
    // MCU -> robot_client.
    chunk.clear();
    for (;;) {
      const ssize_t n = ::read(mcu, buf.data(), buf.size());
      if (n <= 0) break;
      chunk.insert(chunk.end(), buf.begin(), buf.begin() + n);
    }
    if (down.stalled) {
      down.cut += chunk.size();
      chunk.clear();
    }
    if (garbage_per_s > 0 && !down.stalled && dmg.chance(garbage_per_s * poll_s)) dmg.garbage(chunk, down);
    if (!chunk.empty()) {
      dmg.corrupt(chunk, down);
      const std::size_t w = host.write(chunk);
      down.dropped += chunk.size() - w;
    }
    // robot_client -> MCU.
    chunk.clear();
    for (;;) {
      const std::size_t n = host.read(buf);
      if (n == 0) break;
      chunk.insert(chunk.end(), buf.begin(), buf.begin() + static_cast<long>(n));
    }
    if (up.stalled) {
      up.cut += chunk.size();
      chunk.clear();
    }
    if (garbage_per_s > 0 && !up.stalled && dmg.chance(garbage_per_s * poll_s)) dmg.garbage(chunk, up);
    if (!chunk.empty()) {
      dmg.corrupt(chunk, up);
      const ssize_t w = ::write(mcu, chunk.data(), chunk.size());
      up.dropped += chunk.size() - static_cast<std::size_t>(w > 0 ? w : 0);
    }
  }
  for (const Direction* d : {&down, &up})
    std::printf("serial_relay %-4s: %llu bytes, %llu bits flipped (BER %.2g), %llu garbage bytes, %llu dropped, "
                "%llu cut\n",
                d->name, static_cast<unsigned long long>(d->bytes), static_cast<unsigned long long>(d->flipped_bits),
                d->bytes ? static_cast<double>(d->flipped_bits) / (8.0 * static_cast<double>(d->bytes)) : 0.0,
                static_cast<unsigned long long>(d->garbage_bytes), static_cast<unsigned long long>(d->dropped),
                static_cast<unsigned long long>(d->cut));
  ::close(mcu);
  if (control >= 0) ::close(control);
  return 0;
}
