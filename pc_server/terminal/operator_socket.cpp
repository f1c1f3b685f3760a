#include "pc_server/terminal/operator_socket.hpp"

#include <poll.h>
#include <pwd.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <iostream>
#include <streambuf>

#include "pc_server/terminal/line_reader.hpp"
#include "shared/util/startup_error.hpp"
#include "shared/util/log.hpp"

namespace inspect::server {

namespace {

// An ostream buffer that writes to a socket; a gone peer just drops output.
class FdBuf : public std::streambuf {
 public:
  explicit FdBuf(int fd) : fd_(fd) { setp(buf_, buf_ + sizeof buf_); }
  ~FdBuf() override { sync(); }

 protected:
  int overflow(int ch) override {
    if (sync() != 0) return traits_type::eof();
    if (ch != traits_type::eof()) {
      *pptr() = static_cast<char>(ch);
      pbump(1);
    }
    return ch == traits_type::eof() ? 0 : ch;
  }
  int sync() override {
    const char* p = pbase();
    while (p < pptr() && !broken_) {
      const ssize_t n = ::send(fd_, p, static_cast<std::size_t>(pptr() - p), MSG_NOSIGNAL);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) broken_ = true;
      else p += n;
    }
    setp(buf_, buf_ + sizeof buf_);
    return 0;
  }

 private:
  int fd_;
  bool broken_ = false;
  char buf_[4096];
};

sockaddr_un unixAddress(const std::string& path) {
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  if (path.size() >= sizeof a.sun_path)
    throw util::StartupError("--operator-socket '" + path + "': path longer than " +
                       std::to_string(sizeof a.sun_path - 1) + " characters");
  std::memcpy(a.sun_path, path.c_str(), path.size() + 1);
  return a;
}

std::string peerUser(int fd) {
  ucred cred{};
  socklen_t len = sizeof cred;
  if (::getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &cred, &len) != 0) return "unknown";
  passwd pw{};
  passwd* found = nullptr;
  char buf[1024];
  if (::getpwuid_r(cred.uid, &pw, buf, sizeof buf, &found) == 0 && found) return found->pw_name;
  return "uid " + std::to_string(cred.uid);
}
}  // namespace

OperatorSocket::OperatorSocket(std::string path, RobotRegistry& registry, CommandSink& sink, ControlArbiter& control,
                               Console::Options options, Configure configure)
    : path_(std::move(path)),
      registry_(registry),
      sink_(sink),
      control_(control),
      options_(options),
      configure_(std::move(configure)) {}

OperatorSocket::~OperatorSocket() { stop(); }

void OperatorSocket::start() {
  const sockaddr_un addr = unixAddress(path_);
  // A socket file left by a server that died is replaced; a live server's is not.
  if (const int probe = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0); probe >= 0) {
    const bool live = ::connect(probe, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) == 0;
    ::close(probe);
    if (live) throw util::StartupError("--operator-socket '" + path_ + "': another pc_server is listening there");
    struct stat st {};
    if (::lstat(path_.c_str(), &st) == 0) {
      if (!S_ISSOCK(st.st_mode))
        throw util::StartupError("--operator-socket '" + path_ + "': exists and is not a socket (not replaced)");
      ::unlink(path_.c_str());
    }
  }
  listen_fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (listen_fd_ < 0) throw util::StartupError("--operator-socket: socket(): " + std::string(std::strerror(errno)));
  const mode_t old = ::umask(0117);  // rw for the owner and group: file permissions decide who may attach
  const int rc = ::bind(listen_fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr);
  ::umask(old);
  if (rc != 0 || ::listen(listen_fd_, 8) != 0) {
    const std::string why = std::strerror(errno);
    ::close(listen_fd_);
    listen_fd_ = -1;
    throw util::StartupError("--operator-socket '" + path_ + "': " + why);
  }
  acceptor_ = std::thread([this] { acceptLoop(); });
}

void OperatorSocket::stop() {
  if (stopping_.exchange(true)) return;
  if (acceptor_.joinable()) acceptor_.join();
  {
    std::lock_guard lk(mu_);
    for (auto& s : sessions_) {
      s->stop.request();
      ::shutdown(s->fd, SHUT_RDWR);
    }
  }
  for (auto& s : sessions_) {
    if (s->thread.joinable()) s->thread.join();
  }
  sessions_.clear();
  if (listen_fd_ >= 0) {
    ::close(listen_fd_);
    listen_fd_ = -1;
    ::unlink(path_.c_str());
  }
}

void OperatorSocket::acceptLoop() {
  while (!stopping_) {
    pollfd p{listen_fd_, POLLIN, 0};
    if (::poll(&p, 1, 100) <= 0) continue;
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
    if (fd < 0) continue;
    std::lock_guard lk(mu_);
    // Reap finished sessions.
    for (auto it = sessions_.begin(); it != sessions_.end();) {
      if ((*it)->done) {
        (*it)->thread.join();
        it = sessions_.erase(it);
      } else {
        ++it;
      }
    }
    if (live_.load() >= kMaxSessions) {
      const std::string msg = "pc_server: too many operator sessions (" + std::to_string(kMaxSessions) + ")\n";
      (void)!::send(fd, msg.data(), msg.size(), MSG_NOSIGNAL);
      ::close(fd);
      continue;
    }
    auto s = std::make_unique<Session>();
    s->fd = fd;
    Session& ref = *s;
    ++live_;
    s->thread = std::thread([this, &ref] {
      runSession(ref);
      ::close(ref.fd);
      --live_;
      ref.done = true;
    });
    sessions_.push_back(std::move(s));
  }
}

void OperatorSocket::runSession(Session& s) {
  const std::string user = peerUser(s.fd);
  const uint64_t id = control_.openSession(user);
  const std::string name = control_.sessionName(id);
  log::info(log::tag::kOperator, name, " attached");
  FdBuf buf(s.fd);
  std::ostream out(&buf);
  {
    Console::Options o = options_;
    o.drive_lease_s = kDriveLease_s;  // silence from the attached operator stops its `drive`
    Console console(registry_, sink_, out, s.stop, o);
    console.setSession(&control_, id);
    console.eventsFromNow();
    if (configure_) configure_(console);
    out << "pc_server operator session: " << name
        << ". 'help' lists the commands, 'control' shows who controls each robot, 'quit' detaches.\n";
    out.flush();
    LineReader reader(s.fd, s.stop, kMaxLine);
    // While a command runs (a wait, an Ack), input still arriving on the
    // socket (keep-alives, the next lines) says the operator is there.
    int pending = 0;
    console.setIdleHook([&] {
      int n = 0;
      if (::ioctl(s.fd, FIONREAD, &n) == 0 && n > pending) console.operatorPresent();
      pending = std::max(pending, n);
    });
    int line_no = 0;
    while (!console.quitRequested()) {
      std::string line;
      const auto r = reader.nextLine(line, 100);
      pending = 0;  // what was queued is being read
      if (r == LineReader::Result::kStopped || r == LineReader::Result::kEof) break;  // EOF: the operator left
      if (r == LineReader::Result::kTimeout) {
        console.pump();  // events and notes keep printing while the operator is quiet
        continue;
      }
      console.operatorPresent();  // every line, the attach client's keep-alives included
      if (r == LineReader::Result::kData && (line.empty() || line == "\r")) {  // a keep-alive
        console.pump();  // events and notes keep printing
        continue;
      }
      ++line_no;
      if (r == LineReader::Result::kTooLong) {
        out << "error: line longer than " << kMaxLine << " characters ignored\n";
      } else {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        console.execute(line, line_no);
      }
      out.flush();
      console.pump();
    }
    out.flush();
  }
  // Leaving gives its robots free; a teleop set-point of this session stops with it.
  for (const auto& robot : control_.closeSession(id)) sink_.clearTeleop(robot);
  log::info(log::tag::kOperator, name, " detached");
}

int attachToOperatorSocket(const std::string& path) {
  sockaddr_un addr{};
  try {
    addr = unixAddress(path);
  } catch (const std::exception& e) {
    std::cerr << "pc_server: " << e.what() << std::endl;
    return 3;
  }
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0 || ::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    std::cerr << "pc_server: --attach '" << path << "': " << std::strerror(errno)
              << " (is pc_server running with --operator-socket " << path << "?)" << std::endl;
    if (fd >= 0) ::close(fd);
    return 3;
  }
  bool stdin_open = true;
  bool at_line_start = true;  // a keep-alive never splits a line being forwarded
  char buf[4096];
  auto next_keepalive = std::chrono::steady_clock::now();
  for (;;) {
    // While this process runs, an empty line every kKeepAlivePeriod says the
    // operator is there (their `drive` stays leased); a stopped or hung attach
    // lets it lapse within OperatorSocket::kDriveLease_s.
    if (stdin_open && at_line_start && std::chrono::steady_clock::now() >= next_keepalive) {
      if (::send(fd, "\n", 1, MSG_NOSIGNAL) != 1) break;
      next_keepalive = std::chrono::steady_clock::now() + OperatorSocket::kKeepAlivePeriod;
    }
    pollfd p[2] = {{fd, POLLIN, 0}, {0, static_cast<short>(stdin_open ? POLLIN : 0), 0}};
    const int timeout_ms = static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(OperatorSocket::kKeepAlivePeriod).count());
    if (::poll(p, stdin_open ? 2 : 1, timeout_ms) < 0) {
      if (errno == EINTR) continue;
      break;
    }
    if (p[0].revents & (POLLIN | POLLHUP | POLLERR)) {
      const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
      if (n <= 0) break;  // the session ended
      std::cout.write(buf, n);
      std::cout.flush();
    }
    if (stdin_open && (p[1].revents & (POLLIN | POLLHUP | POLLERR))) {
      const ssize_t n = ::read(0, buf, sizeof buf);
      if (n <= 0) {
        stdin_open = false;
        ::shutdown(fd, SHUT_WR);  // the session runs what it has, then ends
        continue;
      }
      at_line_start = buf[n - 1] == '\n';
      for (ssize_t off = 0; off < n;) {
        const ssize_t w = ::send(fd, buf + off, static_cast<std::size_t>(n - off), MSG_NOSIGNAL);
        if (w <= 0) break;
        off += w;
      }
    }
  }
  ::close(fd);
  return 0;
}

}  // namespace inspect::server
