#include "tests/firmware/qemu_board.hpp"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <stdexcept>

#include "tests/support/paths.hpp"

namespace inspect::test {

QemuBoard::QemuBoard(const std::string& elf, const std::string& dir, const std::vector<std::string>& extra) : dir_(dir) {
  const std::string link = dir + "/usart1";
  std::vector<std::string> argv = {"/bin/bash", srcPath("scripts/mcu_qemu.sh"), "--serial-link", link, "--elf", elf};
  argv.insert(argv.end(), extra.begin(), extra.end());
  script_ = Process::spawn(argv, dir + "/qemu.out", dir + "/qemu.err");
  if (!waitUntil([&] { return exists(link); }, 20.0))
    throw std::runtime_error("mcu_qemu.sh made no serial line in 20 s: " + errors());
  fd_ = ::open(link.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
  if (fd_ < 0) throw std::runtime_error("cannot open " + link);
  termios t{};
  if (tcgetattr(fd_, &t) != 0) throw std::runtime_error("tcgetattr " + link);
  cfmakeraw(&t);
  if (tcsetattr(fd_, TCSANOW, &t) != 0) throw std::runtime_error("tcsetattr " + link);
}

QemuBoard::~QemuBoard() {
  if (fd_ >= 0) ::close(fd_);
  script_.terminate(5.0);
}

void QemuBoard::pump(double seconds) {
  const int64_t end = nowNs() + static_cast<int64_t>(seconds * 1e9);
  for (int64_t now; (now = nowNs()) < end;) {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>((end - now) / 1000000 + 1)) <= 0) continue;
    uint8_t buf[512];
    const ssize_t n = ::read(fd_, buf, sizeof buf);
    if (n <= 0) continue;
    const int64_t t = nowNs();
    decoder_.feed(std::span<const uint8_t>(buf, static_cast<std::size_t>(n)), [&](const serial::Message& m, uint8_t) {
      if (const auto* f = std::get_if<serial::SensorFrame>(&m)) frames_.push_back({t, *f});
    });
  }
}

void QemuBoard::send(const serial::Message& m) {
  const auto f = encoder_.encode(m);
  write(f.span());
  if (std::holds_alternative<serial::WheelCommand>(m)) {
    next_wheel_seq_ = static_cast<uint8_t>(f.seq + 1);
    last_wheel_ns_ = nowNs();
  }
}

void QemuBoard::write(std::span<const uint8_t> bytes) {
  if (::write(fd_, bytes.data(), bytes.size()) != static_cast<ssize_t>(bytes.size()))
    throw std::runtime_error("short write to the board's serial line");
}

void QemuBoard::drive(double seconds, int16_t left_mrad_s, int16_t right_mrad_s) {
  const int periods = static_cast<int>(seconds / 0.02 + 0.5);
  for (int i = 0; i < periods; ++i) {
    send(serial::WheelCommand{left_mrad_s, right_mrad_s, serial::WheelCommand::kEnable});
    if (i % 5 == 0) send(serial::Heartbeat{static_cast<uint32_t>(nowNs() / 1000000)});
    pump(0.02);
  }
}

std::string QemuBoard::stop(double timeout_s) {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  script_.terminate(timeout_s);
  return readFile(dir_ + "/qemu.out");
}

std::string QemuBoard::waitForEnd(double timeout_s) {
  if (!script_.wait(timeout_s)) return "";
  return readFile(dir_ + "/qemu.out");
}

std::string QemuBoard::errors() const { return readFile(dir_ + "/qemu.err"); }

}  // namespace inspect::test
