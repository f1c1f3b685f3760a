// bench_video: glass-to-glass latency of the robot's video path against
// GStreamer, on loopback, with the same synthetic frames (SyntheticSource:
// a moving scene with the machine-readable time code), per picture size:
//   (a) this system: VideoSender (capture -> encode -> RTP -> UDP) and
//       VideoReceiver (UDP -> depacketize -> decode -> BGR) in two processes
//       of their own (this program re-executed with --role), latency = time
//       the decoded picture reached the frame hook - capture time read from
//       the picture;
//   (b) GStreamer: `x264enc tune=zerolatency speed-preset=ultrafast !
//       rtph264pay config-interval=-1 ! udpsink` into `udpsrc ! rtph264depay
//       ! avdec_h264`, two gst-launch-1.0 processes fed raw I420 through a
//       pipe and read back through a pipe, latency measured the same way;
//   (p) the cost of those two pipes alone: raw frames through
//       `fdsrc ! fdsink`, from the start of the write to the end of the read;
//   (c) the encode + decode compute floor, in-process, unpaced.
// CPU % = CPU time / wall time over the measured window (100 = one core).
// Not a test (bench_video_smoke runs it briefly).
#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <functional>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/udp.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "shared/util/clock.hpp"
#include "shared/video/frame_source.hpp"
#include "shared/video/h264_codec.hpp"
#include "shared/video/timecode.hpp"
#include "shared/video/video_receiver.hpp"
#include "shared/video/video_sender.hpp"

namespace {

using Clock = std::chrono::steady_clock;
using Json = nlohmann::ordered_json;
using namespace inspect;
using namespace inspect::video;

constexpr const char* kUsage =
    "usage: bench_video [--seconds N] [--sizes WxH,...] [--fps F] [--bitrate-kbps K]\n"
    "                   [--warmup S] [--gst-threads LIST] [--json FILE]\n"
    "Glass-to-glass latency (capture -> decoded picture, read from the time code in the\n"
    "picture) and CPU of (a) this system's VideoSender/VideoReceiver in two processes,\n"
    "(b) the same frames through GStreamer x264enc/rtph264pay/udpsink -> udpsrc/rtph264depay/\n"
    "avdec_h264 (gst-launch-1.0), (p) the cost of (b)'s two pipes alone, and (c) the\n"
    "in-process encode+decode floor, on loopback; prints a table per size and the ratios.\n"
    "Sizes: width a multiple of 8, height even, 64..4096.\n"
    "Defaults: --seconds 10 (measured, per case, after --warmup 1), --sizes 640x480,1280x720,\n"
    "--fps 30, --bitrate-kbps 2000, --gst-threads default (avdec_h264 variants, e.g. default,1:\n"
    "'default' is the plain pipeline, a number N adds max-threads=N).\n"
    "Exit status: 0, 1 when a case failed (the others still run), 2 on bad arguments.\n"
    "Internal: --role sender|receiver [--port P] [--max-seconds S]: the two processes of (a).\n";

constexpr uint32_t kSsrc = 0x5EB1DE0u;
constexpr double kTailS = 0.3;          // after the window, for the last frames to arrive
constexpr double kStartTimeoutS = 10;   // a child's first sign of life
constexpr double kWriteTimeoutS = 2;    // a pipe that takes no frame for this long is stuck

struct Options {
  double seconds = 10;
  double warmup = 1;
  std::vector<cv::Size> sizes{{640, 480}, {1280, 720}};
  double fps = 30;
  int bitrate_kbps = 2000;
  std::vector<int> gst_threads{-1};  // avdec_h264 max-threads variants, -1 = its default
  std::string json_path;
  // --role
  std::string role;
  uint16_t port = 0;
  double max_seconds = 120;  // a role process ends by itself after this
};

int gop(const Options& o) { return std::max(1, static_cast<int>(std::lround(o.fps))); }

/// The encoder of (a) and (c): the library's defaults (libx264 ultrafast
/// zerolatency, one thread) with this run's size, rate, bitrate and GOP.
EncoderSettings encoderSettings(const Options& o, cv::Size sz) {
  EncoderSettings es;
  es.width = sz.width;
  es.height = sz.height;
  es.fps = o.fps;
  es.bitrate_kbps = o.bitrate_kbps;
  es.gop = gop(o);
  return es;
}

std::string sizeName(cv::Size s) { return std::to_string(s.width) + "x" + std::to_string(s.height); }
double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
Clock::duration toDuration(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}
Json numberOrNull(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }
/// `v` printed with `fmt`, "-" when not a number.
std::string cell(double v, const char* fmt = "%.2f") {
  if (!std::isfinite(v)) return "-";
  char b[32];
  std::snprintf(b, sizeof b, fmt, v);
  return b;
}

// ---------------------------------------------------------------- figures

/// One picture that came out of a pipeline.
struct FrameRecord {
  uint64_t arrive_us = 0;       // when the decoded picture was in hand (monoNowUs)
  uint64_t capture_us = 0;      // read from the picture's time code; 0 = unreadable
  uint32_t index = 0;           // frame index from the time code
  uint64_t ext_capture_us = 0;  // RTP capture-time extension (this system only), 0 = none
};

struct Latency {
  uint64_t frames = 0;      // readable pictures captured in the window
  uint64_t lost = 0;        // frame index gaps among them
  uint64_t unreadable = 0;  // pictures that arrived in the window with no readable time code
  double median_ms = NAN, p99_ms = NAN;
};

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5);
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

Latency fromSamples(const std::vector<double>& ms) {
  Latency l;
  l.frames = ms.size();
  l.median_ms = percentile(ms, 0.5);
  l.p99_ms = percentile(ms, 0.99);
  return l;
}

/// Latency of the pictures captured in [t0, t1): arrival - capture, where the
/// capture time is the picture's time code, or the RTP extension when `ext`.
Latency summarize(const std::vector<FrameRecord>& recs, uint64_t t0, uint64_t t1, bool ext = false) {
  std::vector<double> ms;
  std::vector<uint32_t> idx;
  uint64_t unreadable = 0;
  for (const auto& r : recs) {
    const uint64_t cap = ext ? r.ext_capture_us : r.capture_us;
    if (cap == 0) {
      if (r.arrive_us >= t0 && r.arrive_us < t1) ++unreadable;
      continue;
    }
    if (cap < t0 || cap >= t1) continue;
    ms.push_back(static_cast<double>(static_cast<int64_t>(r.arrive_us - cap)) / 1000.0);
    if (r.capture_us) idx.push_back(r.index);
  }
  Latency l = fromSamples(ms);
  l.unreadable = unreadable;
  std::sort(idx.begin(), idx.end());
  idx.erase(std::unique(idx.begin(), idx.end()), idx.end());
  if (!idx.empty()) l.lost = (uint64_t{idx.back()} - idx.front() + 1) - idx.size();
  return l;
}

Json toJson(const Latency& l) {
  return Json{{"frames", l.frames}, {"lost", l.lost}, {"unreadable", l.unreadable},
              {"median_ms", numberOrNull(l.median_ms)}, {"p99_ms", numberOrNull(l.p99_ms)}};
}

/// One row of the table.
struct CaseResult {
  CaseResult(std::string k, std::string t, std::string ti)
      : key(std::move(k)), tag(std::move(t)), title(std::move(ti)) {}
  std::string key;    // JSON name
  std::string tag;    // "(a)", for the ratios
  std::string title;  // table row
  std::string error;  // "" = it ran
  Latency lat;
  double cpu_send = NAN, cpu_recv = NAN;
  double cpu_other = NAN;  // the rest of the machine (other users) over the window
  std::vector<std::string> notes;  // printed under the table
  Json detail = Json::object();
};

CaseResult failed(CaseResult r, const std::string& why) {
  r.error = why;
  return r;
}

// ---------------------------------------------------------------- CPU time

double timespecSeconds(const timespec& ts) { return static_cast<double>(ts.tv_sec) + ts.tv_nsec * 1e-9; }

/// utime + stime of a process (all its threads) in seconds; NAN when unreadable.
double processCpuSeconds(pid_t pid) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/stat");
  std::string s((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  const auto close = s.rfind(')');
  if (close == std::string::npos) return NAN;
  std::istringstream rest(s.substr(close + 2));
  std::string field;
  unsigned long long utime = 0, stime = 0;
  // Fields after the name start at 3 (state); utime and stime are 14 and 15.
  for (int i = 3; i <= 15 && rest >> field; ++i) {
    if (i == 14) utime = std::strtoull(field.c_str(), nullptr, 10);
    if (i == 15) stime = std::strtoull(field.c_str(), nullptr, 10);
  }
  return static_cast<double>(utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

std::function<double()> threadCpu(std::thread& t) {
  clockid_t cid;
  if (pthread_getcpuclockid(t.native_handle(), &cid) != 0) return [] { return NAN; };
  return [cid] {
    timespec ts{};
    return clock_gettime(cid, &ts) == 0 ? timespecSeconds(ts) : NAN;
  };
}

double processCpuSelf() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return timespecSeconds(ts);
}

/// CPU seconds all cores of the machine have been busy (/proc/stat); NAN when unreadable.
double machineBusySeconds() {
  std::ifstream f("/proc/stat");
  std::string cpu;
  unsigned long long user = 0, nice = 0, system = 0, idle = 0, iowait = 0, irq = 0, softirq = 0, steal = 0;
  if (!(f >> cpu >> user >> nice >> system >> idle >> iowait >> irq >> softirq >> steal) || cpu != "cpu") return NAN;
  return static_cast<double>(user + nice + system + irq + softirq + steal) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

/// CPU % (of one core) the rest of the machine used between two samples of
/// (machine busy, ours) seconds over `wall_s`.
double otherPct(double machine0, double machine1, double ours0, double ours1, double wall_s) {
  return std::max(0.0, 100.0 * ((machine1 - machine0) - (ours1 - ours0)) / wall_s);
}

// ---------------------------------------------------------------- child processes

/// A child process with optional pipes to its stdin and from its stdout; its
/// stderr goes to an unlinked temporary file (errorText()). It gets SIGKILL
/// when this process dies; the destructor ends it.
class Child {
 public:
  Child() = default;
  ~Child() { stop(0.5); }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  /// Starts `argv` (argv[0] is a path). "" or why it did not start.
  std::string start(const std::vector<std::string>& argv, bool pipe_stdin, bool pipe_stdout) {
    name_ = argv.at(0).substr(argv[0].rfind('/') + 1);
    int in[2] = {-1, -1}, out[2] = {-1, -1};
    char tmpl[] = "/tmp/bench_video_stderr_XXXXXX";
    err_ = mkostemp(tmpl, O_CLOEXEC);
    if (err_ < 0) return "cannot create a temporary file: " + std::string(std::strerror(errno));
    unlink(tmpl);
    if ((pipe_stdin && pipe2(in, O_CLOEXEC) != 0) || (pipe_stdout && pipe2(out, O_CLOEXEC) != 0)) {
      const std::string why = "pipe: " + std::string(std::strerror(errno));
      for (int fd : {in[0], in[1]})
        if (fd >= 0) close(fd);
      return why;
    }
    const int devnull = open("/dev/null", O_RDWR | O_CLOEXEC);
    for (int fd : {in[1], out[0]})
      if (fd >= 0) fcntl(fd, F_SETPIPE_SZ, 1 << 20);  // fewer wake-ups per frame; best effort
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    const pid_t parent = getpid();
    pid_ = fork();
    if (pid_ == 0) {  // only async-signal-safe calls until exec
      dup2(pipe_stdin ? in[0] : devnull, 0);
      dup2(pipe_stdout ? out[1] : devnull, 1);
      dup2(err_, 2);
      prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (getppid() != parent) _exit(127);
      struct sigaction dfl {};
      dfl.sa_handler = SIG_DFL;
      sigaction(SIGPIPE, &dfl, nullptr);
      execv(args[0], args.data());
      const char msg[] = "bench_video: exec failed\n";
      (void)!write(2, msg, sizeof msg - 1);
      _exit(127);
    }
    const int fork_errno = errno;
    for (int fd : {in[0], out[1], devnull})
      if (fd >= 0) close(fd);
    in_ = in[1];
    out_ = out[0];
    if (pid_ < 0) return "fork: " + std::string(std::strerror(fork_errno));
    if (in_ >= 0) fcntl(in_, F_SETFL, fcntl(in_, F_GETFL) | O_NONBLOCK);
    return {};
  }

  pid_t pid() const { return pid_; }
  int in() const { return in_; }
  int out() const { return out_; }
  const std::string& name() const { return name_; }
  void closeIn() {
    if (in_ >= 0) close(in_);
    in_ = -1;
  }

  /// False once it has exited (reaped here).
  bool alive() {
    if (pid_ <= 0 || exited_) return false;
    if (waitpid(pid_, &status_, WNOHANG) == pid_) exited_ = true;
    return !exited_;
  }

  /// Closes its stdin, waits `grace_s` for it to exit, then SIGTERM, then
  /// SIGKILL after another `grace_s`. Idempotent.
  void stop(double grace_s) {
    closeIn();
    if (pid_ > 0 && !exited_) {
      waitExit(grace_s);
      if (!exited_) {
        kill(pid_, SIGTERM);
        waitExit(grace_s);
      }
      if (!exited_) {
        kill(pid_, SIGKILL);
        if (waitpid(pid_, &status_, 0) == pid_) exited_ = true;
      }
    }
    if (err_ >= 0) stderr_text_ = readErr();
    for (int* fd : {&out_, &err_})
      if (*fd >= 0) close(std::exchange(*fd, -1));
  }

  /// Waits up to `s` seconds for it to exit.
  bool waitExit(double s) {
    const auto until = Clock::now() + toDuration(s);
    while (alive() && Clock::now() < until) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    return !alive();
  }

  /// "exit N" / "signal N" once it ended, else "running".
  std::string how() const {
    if (!exited_) return "running";
    if (WIFEXITED(status_)) return "exit " + std::to_string(WEXITSTATUS(status_));
    return "signal " + std::to_string(WTERMSIG(status_));
  }
  bool exitedCleanly() const { return exited_ && WIFEXITED(status_) && WEXITSTATUS(status_) == 0; }

  /// The last lines it wrote on stderr (one line, for reports).
  std::string errorText() const {
    std::string t = err_ >= 0 ? readErr() : stderr_text_;
    while (!t.empty() && (t.back() == '\n' || t.back() == ' ')) t.pop_back();
    if (t.size() > 600) t = "..." + t.substr(t.size() - 600);
    std::replace(t.begin(), t.end(), '\n', '|');
    return name_ + " (" + how() + ")" + (t.empty() ? "" : ": " + t);
  }

  std::function<double()> cpu() const {
    const pid_t p = pid_;
    return [p] { return processCpuSeconds(p); };
  }

 private:
  std::string readErr() const {
    std::string t;
    char buf[4096];
    off_t off = 0;
    for (ssize_t n; (n = pread(err_, buf, sizeof buf, off)) > 0; off += n) t.append(buf, static_cast<std::size_t>(n));
    return t;
  }

  std::string name_;
  pid_t pid_ = -1;
  int in_ = -1, out_ = -1, err_ = -1;
  bool exited_ = false;
  int status_ = 0;
  std::string stderr_text_;
};

/// Reads exactly `n` bytes of `fd` into `buf`; false on EOF, a read error or `stop()`.
bool readFully(int fd, uint8_t* buf, std::size_t n, const std::function<bool()>& stop) {
  std::size_t have = 0;
  while (have < n) {
    if (stop()) return false;
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, 100) <= 0) continue;
    const ssize_t k = read(fd, buf + have, n - have);
    if (k == 0 || (k < 0 && errno != EINTR && errno != EAGAIN)) return false;
    if (k > 0) have += static_cast<std::size_t>(k);
  }
  return true;
}

/// One line from `fd` (without the newline), by `deadline`; false on EOF or time out.
bool readLine(int fd, std::string& pending, std::string& line, Clock::time_point deadline) {
  for (;;) {
    if (const auto nl = pending.find('\n'); nl != std::string::npos) {
      line = pending.substr(0, nl);
      pending.erase(0, nl + 1);
      return true;
    }
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) return false;
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, static_cast<int>(std::min<long long>(left, 100))) <= 0) continue;
    char buf[65536];
    const ssize_t k = read(fd, buf, sizeof buf);
    if (k == 0 || (k < 0 && errno != EINTR && errno != EAGAIN)) return false;
    if (k > 0) pending.append(buf, static_cast<std::size_t>(k));
  }
}

/// Writes all of `data` to the non-blocking `fd`; false when it fails or takes
/// more than kWriteTimeoutS.
bool writeAll(int fd, const uint8_t* data, std::size_t n, std::string& error) {
  const auto deadline = Clock::now() + toDuration(kWriteTimeoutS);
  std::size_t done = 0;
  while (done < n) {
    const ssize_t k = write(fd, data + done, n - done);
    if (k > 0) {
      done += static_cast<std::size_t>(k);
      continue;
    }
    if (k < 0 && errno != EAGAIN && errno != EINTR) {
      error = std::string("pipe write: ") + std::strerror(errno);
      return false;
    }
    if (Clock::now() > deadline) {
      error = "pipe write: the pipeline took no input for " + cell(kWriteTimeoutS, "%g") + " s";
      return false;
    }
    pollfd p{fd, POLLOUT, 0};
    poll(&p, 1, 50);
  }
  return true;
}

std::string selfPath() {
  char buf[4096];
  const ssize_t n = readlink("/proc/self/exe", buf, sizeof buf - 1);
  return n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : std::string();
}

/// `prog` looked up on PATH; "" when absent.
std::string findOnPath(const std::string& prog) {
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path ? path : "/usr/bin:/bin");
  for (std::string d; std::getline(dirs, d, ':');) {
    const std::string p = (d.empty() ? "." : d) + "/" + prog;
    if (access(p.c_str(), X_OK) == 0) return p;
  }
  return {};
}

/// A UDP port that was free a moment ago on 127.0.0.1 (0 when none).
uint16_t freeUdpPort() {
  boost::asio::io_context io;
  boost::asio::ip::udp::socket s(io);
  boost::system::error_code ec;
  s.open(boost::asio::ip::udp::v4(), ec);
  if (!ec) s.bind({boost::asio::ip::address_v4::loopback(), 0}, ec);
  return ec ? 0 : s.local_endpoint(ec).port();
}

/// True once some socket is bound to UDP `port` (IPv4, /proc/net/udp).
bool udpPortBound(uint16_t port) {
  std::ifstream f("/proc/net/udp");
  char want[8];
  std::snprintf(want, sizeof want, ":%04X", port);
  for (std::string line; std::getline(f, line);) {
    std::istringstream ls(line);
    std::string sl, local;
    if (ls >> sl >> local && local.size() > 5 && local.substr(local.size() - 5) == want) return true;
  }
  return false;
}

// ---------------------------------------------------------------- measured window

/// CPU % of each probe over the measured window.
struct Window {
  uint64_t t0_us = 0, t1_us = 0;
  std::vector<double> cpu_pct;
  double other_pct = NAN;  // the rest of the machine
  std::string error;  // a child died, or `check` failed
};

/// Waits out the warm-up from now, then the measured window, sampling the CPU
/// probes at both ends; stops early when one of `kids` exits or `check`
/// returns an error.
Window measureWindow(const Options& o, const std::vector<Child*>& kids,
                     const std::vector<std::function<double()>>& probes,
                     const std::function<std::string()>& check = {}) {
  Window w;
  const auto start = Clock::now();
  const auto watchUntil = [&](Clock::time_point until) {
    while (Clock::now() < until) {
      for (Child* k : kids)
        if (!k->alive()) {
          w.error = k->name() + " ended early: " + k->errorText();
          return false;
        }
      if (check)
        if (w.error = check(); !w.error.empty()) return false;
      std::this_thread::sleep_for(std::min<Clock::duration>(std::chrono::milliseconds(20), until - Clock::now()));
    }
    return true;
  };
  if (!watchUntil(start + toDuration(o.warmup))) return w;
  // Ours = this process and the children.
  const auto ours = [&] {
    double s = processCpuSelf();
    for (Child* k : kids) s += processCpuSeconds(k->pid());
    return s;
  };
  std::vector<double> c0;
  for (const auto& p : probes) c0.push_back(p());
  const double machine0 = machineBusySeconds(), ours0 = ours();
  const auto wall0 = Clock::now();
  w.t0_us = monoNowUs();
  if (!watchUntil(wall0 + toDuration(o.seconds))) return w;
  w.t1_us = monoNowUs();
  const double wall = secondsSince(wall0);
  for (std::size_t i = 0; i < probes.size(); ++i) w.cpu_pct.push_back(100.0 * (probes[i]() - c0[i]) / wall);
  w.other_pct = otherPct(machine0, machineBusySeconds(), ours0, ours(), wall);
  return w;
}

// ---------------------------------------------------------------- (a) this system

/// Waits until stdin reaches EOF (the parent closed it or died) or `max_s`.
void waitForStdinEof(double max_s) {
  const auto until = Clock::now() + toDuration(max_s);
  char buf[256];
  while (Clock::now() < until) {
    pollfd p{0, POLLIN, 0};
    if (poll(&p, 1, 100) > 0 && read(0, buf, sizeof buf) <= 0) return;
  }
}

void printLine(const Json& j) {
  const std::string s = j.dump() + "\n";
  std::fwrite(s.data(), 1, s.size(), stdout);
  std::fflush(stdout);
}

/// --role receiver: VideoReceiver on a free port of 127.0.0.1; prints {"port"},
/// records every decoded picture until stdin closes, then prints the records.
int receiverRole(const Options& o) {
  VideoReceiver rx(ReceiverSettings{.bind = "127.0.0.1", .port = 0});
  std::mutex mu;
  std::vector<FrameRecord> recs;
  rx.setStream("bench", kSsrc, boost::asio::ip::address(), 0);
  rx.setFrameHook([&](const std::string&, const cv::Mat& bgr, uint64_t capture_us) {
    FrameRecord r;
    r.arrive_us = monoNowUs();
    r.ext_capture_us = capture_us;
    if (const auto tc = readTimecode(bgr)) {
      r.capture_us = unwrapCaptureUs(tc->capture_us, r.arrive_us);
      r.index = tc->frame_index;
    }
    std::lock_guard lk(mu);
    recs.push_back(r);
  });
  rx.start();
  printLine(Json{{"port", rx.port()}});
  waitForStdinEof(o.max_seconds);
  rx.stop();
  Json frames = Json::array();
  for (const auto& r : recs) frames.push_back({r.arrive_us, r.capture_us, r.index, r.ext_capture_us});
  Json stats = Json::object();
  if (const auto st = rx.stats("bench"))
    stats = Json{{"decoded", st->decoded}, {"frames", st->frames}, {"frames_dropped", st->frames_dropped},
                 {"frames_skipped", st->frames_skipped}, {"lost_packets", st->lost_packets},
                 {"decode_errors", st->decode_errors}, {"late", st->late}, {"packets", st->packets}};
  printLine(Json{{"frames", frames}, {"stats", stats}});
  return 0;
}

/// --role sender: VideoSender with the synthetic source to 127.0.0.1:port
/// until stdin closes; then prints its counters.
int senderRole(const Options& o) {
  SenderSettings s;
  s.source.uri = "synthetic";
  s.source.width = o.sizes.at(0).width;
  s.source.height = o.sizes.at(0).height;
  s.source.fps = o.fps;
  s.encoder = encoderSettings(o, o.sizes.at(0));
  s.host = "127.0.0.1";
  s.port = o.port;
  s.ssrc = kSsrc;
  VideoSender tx(s);
  tx.start();
  waitForStdinEof(o.max_seconds);
  const SenderStats st = tx.stats();
  tx.stop();
  printLine(Json{{"encoder", st.encoder}, {"captured", st.captured}, {"encoded", st.encoded}, {"dropped", st.dropped},
                 {"keyframes", st.keyframes}, {"packets", st.packets}, {"bytes", st.bytes},
                 {"send_errors", st.send_errors}, {"encode_ms", st.encode_ms}, {"error", st.error}});
  return 0;
}

/// The common arguments of a role process.
std::vector<std::string> roleArgs(const std::string& self, const std::string& role, const Options& o, cv::Size sz) {
  return {self, "--role", role, "--sizes", sizeName(sz), "--fps", std::to_string(o.fps), "--bitrate-kbps",
          std::to_string(o.bitrate_kbps), "--max-seconds", std::to_string(o.warmup + o.seconds + 60)};
}

CaseResult runThisSystem(const Options& o, cv::Size sz, const std::string& self) {
  CaseResult r{"this_system", "(a)", "(a) this system"};
  Child rx, tx;
  std::string rx_pending, tx_pending, line;
  if (auto e = rx.start(roleArgs(self, "receiver", o, sz), true, true); !e.empty()) return failed(r, e);
  if (!readLine(rx.out(), rx_pending, line, Clock::now() + toDuration(kStartTimeoutS)))
    return failed(r, "receiver did not start: " + rx.errorText());
  uint16_t port = 0;
  try {
    port = Json::parse(line).at("port").get<uint16_t>();
  } catch (const nlohmann::json::exception& e) {
    return failed(r, "receiver said '" + line + "': " + e.what());
  }
  auto args = roleArgs(self, "sender", o, sz);
  args.insert(args.end(), {"--port", std::to_string(port)});
  if (auto e = tx.start(args, true, true); !e.empty()) return failed(r, e);
  const Window w = measureWindow(o, {&rx, &tx}, {tx.cpu(), rx.cpu()});
  if (!w.error.empty()) return failed(r, w.error);
  tx.closeIn();
  if (!readLine(tx.out(), tx_pending, line, Clock::now() + toDuration(kStartTimeoutS)))
    return failed(r, "sender gave no figures: " + tx.errorText());
  Json sender, receiver;
  std::vector<FrameRecord> recs;
  try {
    sender = Json::parse(line);
    std::this_thread::sleep_for(toDuration(kTailS));
    rx.closeIn();
    if (!readLine(rx.out(), rx_pending, line, Clock::now() + toDuration(kStartTimeoutS)))
      return failed(r, "receiver gave no figures: " + rx.errorText());
    receiver = Json::parse(line);
    for (const auto& f : receiver.at("frames"))
      recs.push_back({f.at(0).get<uint64_t>(), f.at(1).get<uint64_t>(), f.at(2).get<uint32_t>(),
                      f.at(3).get<uint64_t>()});
  } catch (const nlohmann::json::exception& e) {
    return failed(r, std::string("bad figures from a role process: ") + e.what());
  }
  tx.stop(2);
  rx.stop(2);
  r.lat = summarize(recs, w.t0_us, w.t1_us);
  const Latency ext = summarize(recs, w.t0_us, w.t1_us, true);
  r.cpu_send = w.cpu_pct[0];
  r.cpu_recv = w.cpu_pct[1];
  r.cpu_other = w.other_pct;
  char note[256];
  std::snprintf(note, sizeof note, "(a) latency from the RTP capture-time extension: median %.2f ms, p99 %.2f ms",
                ext.median_ms, ext.p99_ms);
  r.notes.push_back(note);
  std::snprintf(note, sizeof note,
                "(a) sender %s: %llu captured, %llu encoded, %llu dropped in the mailbox; receiver: %llu lost "
                "packets, %llu frames skipped, %llu decode errors",
                sender.value("encoder", "?").c_str(), sender.value("captured", 0ull), sender.value("encoded", 0ull),
                sender.value("dropped", 0ull), receiver["stats"].value("lost_packets", 0ull),
                receiver["stats"].value("frames_skipped", 0ull), receiver["stats"].value("decode_errors", 0ull));
  r.notes.push_back(note);
  r.detail = Json{{"rtp_extension_latency", toJson(ext)}, {"sender", sender}, {"receiver", receiver["stats"]}};
  return r;
}

// ---------------------------------------------------------------- (b) GStreamer

std::vector<std::string> split(const std::string& s) {
  std::istringstream is(s);
  std::vector<std::string> v;
  for (std::string t; is >> t;) v.push_back(t);
  return v;
}

/// "30/1", or "29970/1000" for a fractional rate.
std::string fpsFraction(double fps) {
  if (fps == std::round(fps)) return std::to_string(std::lround(fps)) + "/1";
  return std::to_string(std::lround(fps * 1000)) + "/1000";
}

std::string gstSender(const Options& o, cv::Size sz, const std::string& port) {
  const std::size_t bytes = static_cast<std::size_t>(sz.area()) * 3 / 2;
  std::ostringstream p;
  p << "fdsrc fd=0 blocksize=" << bytes << " ! rawvideoparse width=" << sz.width << " height=" << sz.height
    << " format=i420 framerate=" << fpsFraction(o.fps) << " ! x264enc tune=zerolatency speed-preset=ultrafast"
    << " bitrate=" << o.bitrate_kbps << " key-int-max=" << gop(o)
    << " ! rtph264pay config-interval=-1 ! udpsink host=127.0.0.1 port=" << port << " sync=false";
  return p.str();
}

std::string gstReceiver(const std::string& port, int threads) {
  std::ostringstream p;
  p << "udpsrc port=" << port
    << " caps=application/x-rtp,media=video,clock-rate=90000,encoding-name=H264,payload=96"
    << " ! rtph264depay ! avdec_h264" << (threads >= 0 ? " max-threads=" + std::to_string(threads) : "")
    << " ! videoconvert ! video/x-raw,format=I420 ! fdsink fd=1 sync=false";
  return p.str();
}

std::string gstPassThrough(cv::Size sz) {
  return "fdsrc fd=0 blocksize=" + std::to_string(sz.area() * 3 / 2) + " ! fdsink fd=1 sync=false";
}

/// Starts `gst-launch-1.0 -q <pipeline>`.
std::string startGst(Child& c, const std::string& gst, const std::string& pipeline, bool pipe_in, bool pipe_out) {
  std::vector<std::string> argv{gst, "-q"};
  for (auto& t : split(pipeline)) argv.push_back(t);
  return c.start(argv, pipe_in, pipe_out);
}

/// What feeding raw frames into one child and reading them back from another gave.
struct FeedResult {
  std::vector<FrameRecord> recs;
  Window w;  // cpu_pct: feeder thread, reader thread, then the extra probes
  std::vector<uint64_t> write_us;  // per frame index: when its write into the pipe began
};

/// Feeds the synthetic frames, paced at the frame rate as VideoSender paces
/// them (capture time taken before drawing), as I420 into `into`'s stdin, and
/// reads I420 pictures back from `from`'s stdout, over the warm-up and the
/// measured window. OpenCV runs on one thread here so that the feeder
/// thread's CPU clock holds all of its work.
FeedResult feedAndRead(const Options& o, cv::Size sz, Child& into, Child& from,
                       std::vector<std::function<double()>> probes) {
  FeedResult res;
  const std::size_t bytes = static_cast<std::size_t>(sz.area()) * 3 / 2;
  std::atomic<bool> stop_feed{false}, stop_read{false};
  std::mutex err_mu;
  std::string feed_error;
  const int saved_threads = cv::getNumThreads();
  cv::setNumThreads(1);
  res.write_us.resize(static_cast<std::size_t>((o.warmup + o.seconds + 10) * o.fps) + 10);
  std::thread feeder([&] {
    SyntheticSource src(sz.width, sz.height);
    cv::Mat bgr, i420;
    const auto period = toDuration(1.0 / o.fps);
    auto next = Clock::now();
    for (uint32_t index = 0; !stop_feed && index < res.write_us.size(); ++index) {
      std::this_thread::sleep_until(next);
      next += period;
      if (Clock::now() - next > period) next = Clock::now();  // fell behind: no burst to catch up
      src.read(bgr, monoNowUs(), index);
      cv::cvtColor(bgr, i420, cv::COLOR_BGR2YUV_I420);
      res.write_us[index] = monoNowUs();
      std::string e;
      if (!writeAll(into.in(), i420.data, bytes, e)) {
        std::lock_guard lk(err_mu);
        feed_error = e;
        return;
      }
    }
  });
  std::thread reader([&] {
    std::vector<uint8_t> buf(bytes);
    while (readFully(from.out(), buf.data(), bytes, [&] { return stop_read.load(); })) {
      FrameRecord r;
      r.arrive_us = monoNowUs();
      if (const auto tc = readTimecodeLuma(buf.data(), sz.width, sz.height, sz.width)) {
        r.capture_us = unwrapCaptureUs(tc->capture_us, r.arrive_us);
        r.index = tc->frame_index;
      }
      res.recs.push_back(r);
    }
  });
  probes.insert(probes.begin(), {threadCpu(feeder), threadCpu(reader)});
  std::vector<Child*> kids{&into};
  if (&from != &into) kids.push_back(&from);
  res.w = measureWindow(o, kids, probes, [&] {
    std::lock_guard lk(err_mu);
    return feed_error;
  });
  stop_feed = true;
  feeder.join();
  std::this_thread::sleep_for(toDuration(kTailS));
  stop_read = true;
  reader.join();
  cv::setNumThreads(saved_threads);
  if (res.w.error.empty() && !feed_error.empty()) res.w.error = feed_error;
  return res;
}

CaseResult runGstreamer(const Options& o, cv::Size sz, const std::string& gst, int threads) {
  const std::string tag = threads < 0 ? "(b)" : "(b" + std::to_string(threads) + ")";
  CaseResult r{threads < 0 ? "gstreamer" : "gstreamer_max_threads_" + std::to_string(threads), tag,
               threads < 0 ? "(b) GStreamer" : tag + " GStreamer, avdec max-threads=" + std::to_string(threads)};
  if (gst.empty()) return failed(r, "gst-launch-1.0 not found on PATH");
  const uint16_t port = freeUdpPort();
  if (port == 0) return failed(r, "no free UDP port on 127.0.0.1");
  const std::string send = gstSender(o, sz, std::to_string(port)), recv = gstReceiver(std::to_string(port), threads);
  r.detail = Json{{"sender_pipeline", send}, {"receiver_pipeline", recv}};
  Child rx, tx;
  if (auto e = startGst(rx, gst, recv, false, true); !e.empty()) return failed(r, e);
  const auto until = Clock::now() + toDuration(kStartTimeoutS);
  while (!udpPortBound(port) && rx.alive() && Clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  if (!udpPortBound(port))
    return failed(r, "the receiving pipeline did not bind UDP port " + std::to_string(port) + " within " +
                         cell(kStartTimeoutS, "%g") + " s: " + rx.errorText());
  if (auto e = startGst(tx, gst, send, true, false); !e.empty()) return failed(r, e);
  FeedResult f = feedAndRead(o, sz, tx, rx, {tx.cpu(), rx.cpu()});
  tx.stop(2);  // stdin closed: EOS, exits by itself
  rx.stop(0.2);
  if (!f.w.error.empty()) return failed(r, f.w.error);
  if (!tx.exitedCleanly()) return failed(r, "sending pipeline: " + tx.errorText());
  r.lat = summarize(f.recs, f.w.t0_us, f.w.t1_us);
  const auto& c = f.w.cpu_pct;  // feeder, reader, gst sender, gst receiver
  r.cpu_send = c[0] + c[2];
  r.cpu_recv = c[1] + c[3];
  r.cpu_other = f.w.other_pct;
  r.notes.push_back(tag + " CPU: send = gst-launch " + cell(c[2], "%.1f%%") +
                    " + feeder thread (draw, BGR->I420, pipe write) " + cell(c[0], "%.1f%%") +
                    "; receive = gst-launch " + cell(c[3], "%.1f%%") + " + reader thread (pipe read, time code) " +
                    cell(c[1], "%.1f%%"));
  r.detail["cpu_pct"] = Json{{"gst_sender", c[2]}, {"feeder_thread", c[0]}, {"gst_receiver", c[3]},
                             {"reader_thread", c[1]}};
  return r;
}

/// The cost of the two pipes of (b): raw frames through `fdsrc ! fdsink`,
/// from the start of the write to the end of the read (no drawing).
CaseResult runPipeOverhead(const Options& o, cv::Size sz, const std::string& gst) {
  CaseResult r{"pipe_overhead", "(p)", "(p) pipes of (b) only: fdsrc ! fdsink"};
  if (gst.empty()) return failed(r, "gst-launch-1.0 not found on PATH");
  const std::string pipeline = gstPassThrough(sz);
  r.detail = Json{{"pipeline", pipeline}};
  Child c;
  if (auto e = startGst(c, gst, pipeline, true, true); !e.empty()) return failed(r, e);
  FeedResult f = feedAndRead(o, sz, c, c, {c.cpu()});
  c.stop(2);
  if (!f.w.error.empty()) return failed(r, f.w.error);
  std::vector<FrameRecord> piped;  // those captured in the window, timed from their write
  for (FrameRecord rec : f.recs)
    if (rec.capture_us >= f.w.t0_us && rec.capture_us < f.w.t1_us && rec.index < f.write_us.size()) {
      rec.capture_us = f.write_us[rec.index];
      piped.push_back(rec);
    }
  r.lat = summarize(piped, 0, UINT64_MAX);
  r.cpu_send = f.w.cpu_pct[0] + f.w.cpu_pct[2];  // feeder + the gst process (it both reads and writes)
  r.cpu_recv = f.w.cpu_pct[1];
  r.cpu_other = f.w.other_pct;
  return r;
}

// ---------------------------------------------------------------- (c) floor

CaseResult runFloor(const Options& o, cv::Size sz) {
  CaseResult r{"floor", "(c)", "(c) encode+decode floor"};
  try {
    H264Encoder enc(encoderSettings(o, sz));
    H264Decoder dec;
    SyntheticSource src(sz.width, sz.height);
    const int warm = static_cast<int>(std::lround(o.warmup * o.fps));
    const int n = std::max(1, static_cast<int>(std::lround(o.seconds * o.fps)));
    cv::Mat bgr, out;
    EncodedFrame ef;
    std::vector<double> total, draw_ms, enc_ms, dec_ms;
    double enc_cpu = 0, dec_cpu = 0;
    uint64_t bad = 0;
    double machine0 = NAN, ours0 = NAN;
    Clock::time_point wall0;
    for (int i = 0; i < warm + n; ++i) {
      if (i == warm) {
        machine0 = machineBusySeconds();
        ours0 = processCpuSelf();
        wall0 = Clock::now();
      }
      const auto drawn = Clock::now();
      const uint64_t cap = monoNowUs();
      src.read(bgr, cap, static_cast<uint32_t>(i));
      const auto t0 = Clock::now();
      const double c0 = processCpuSelf();
      const bool got = enc.encode(bgr, cap, static_cast<uint32_t>(i), i == 0, ef);
      const auto t1 = Clock::now();
      const double c1 = processCpuSelf();
      const bool shown = got && dec.decode(ef.annexb.data(), ef.annexb.size(), out);
      const auto t2 = Clock::now();
      const double c2 = processCpuSelf();
      if (i < warm) continue;
      const auto tc = shown ? readTimecode(out) : std::nullopt;
      if (!tc || tc->frame_index != static_cast<uint32_t>(i)) {
        ++bad;
        continue;
      }
      draw_ms.push_back(std::chrono::duration<double, std::milli>(t0 - drawn).count());
      enc_ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
      dec_ms.push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
      total.push_back(std::chrono::duration<double, std::milli>(t2 - t0).count());
      enc_cpu += c1 - c0;
      dec_cpu += c2 - c1;
    }
    r.lat = fromSamples(total);
    r.lat.lost = bad;  // pictures that did not come back intact
    // CPU a stream at the frame rate would need: CPU per frame x fps.
    const double stream_s = static_cast<double>(std::max<std::size_t>(1, total.size())) / o.fps;
    r.cpu_send = 100.0 * enc_cpu / stream_s;
    r.cpu_recv = 100.0 * dec_cpu / stream_s;
    r.cpu_other = otherPct(machine0, machineBusySeconds(), ours0, processCpuSelf(), secondsSince(wall0));
    const double em = percentile(enc_ms, 0.5), dm = percentile(dec_ms, 0.5), drm = percentile(draw_ms, 0.5);
    char note[300];
    std::snprintf(note, sizeof note,
                  "(c) %s encode median %.2f ms (p99 %.2f), decode+BGR median %.2f ms (p99 %.2f); CPU %% = CPU per "
                  "frame x fps. Drawing a frame (in (a) and (b), not in (c)): median %.2f ms",
                  enc.codecName().c_str(), em, percentile(enc_ms, 0.99), dm, percentile(dec_ms, 0.99), drm);
    r.notes.push_back(note);
    r.detail = Json{{"encoder", enc.codecName()}, {"draw_median_ms", numberOrNull(drm)},
                    {"encode_median_ms", numberOrNull(em)},
                    {"encode_p99_ms", numberOrNull(percentile(enc_ms, 0.99))}, {"decode_median_ms", numberOrNull(dm)},
                    {"decode_p99_ms", numberOrNull(percentile(dec_ms, 0.99))}};
  } catch (const VideoError& e) {
    return failed(r, e.what());
  }
  return r;
}

// ---------------------------------------------------------------- report

/// The 1-minute load average (other work on the machine skews the figures).
double loadAverage() {
  std::ifstream f("/proc/loadavg");
  double l = NAN;
  f >> l;
  return l;
}

double ratio(double a, double b) { return std::isfinite(a) && std::isfinite(b) && b > 0 ? a / b : NAN; }

Json ratioJson(const CaseResult& a, const CaseResult& b) {
  return Json{{"median", numberOrNull(ratio(a.lat.median_ms, b.lat.median_ms))},
              {"p99", numberOrNull(ratio(a.lat.p99_ms, b.lat.p99_ms))}};
}

/// Prints one size's table; returns its JSON. `load` = load average before and after.
Json report(const Options& o, cv::Size sz, const std::vector<CaseResult>& cases, std::pair<double, double> load) {
  std::printf("\n== %s @ %g fps, %d kbit/s, GOP %d, loopback: %g s measured after %g s warm-up; load average "
              "%.2f -> %.2f on %u cores ==\n",
              sizeName(sz).c_str(), o.fps, o.bitrate_kbps, gop(o), o.seconds, o.warmup, load.first, load.second,
              std::thread::hardware_concurrency());
  std::printf("%-40s %7s %5s %10s %8s %10s %10s %10s\n", "case", "frames", "lost", "median ms", "p99 ms", "CPU% send",
              "CPU% recv", "CPU% other");
  Json jcases = Json::object();
  for (const auto& c : cases) {
    std::printf("%-40s %7llu %5llu %10s %8s %10s %10s %10s%s\n", c.title.c_str(),
                static_cast<unsigned long long>(c.lat.frames), static_cast<unsigned long long>(c.lat.lost),
                cell(c.lat.median_ms).c_str(), cell(c.lat.p99_ms).c_str(), cell(c.cpu_send, "%.1f").c_str(),
                cell(c.cpu_recv, "%.1f").c_str(), cell(c.cpu_other, "%.1f").c_str(), c.error.empty() ? "" : "  FAILED");
    Json j{{"title", c.title}, {"error", c.error.empty() ? Json(nullptr) : Json(c.error)}};
    j.update(toJson(c.lat));
    j["cpu_send_pct"] = numberOrNull(c.cpu_send);
    j["cpu_recv_pct"] = numberOrNull(c.cpu_recv);
    j["cpu_other_pct"] = numberOrNull(c.cpu_other);
    j.update(c.detail);
    jcases[c.key] = j;
  }
  Json jratios = Json::object();
  const CaseResult& a = cases.front();
  for (const auto& c : cases) {
    if (&c == &a || c.key == "pipe_overhead") continue;
    const Json rj = ratioJson(a, c);
    std::printf("ratio %s/%-5s latency median %6sx   p99 %6sx\n", a.tag.c_str(), c.tag.c_str(),
                cell(ratio(a.lat.median_ms, c.lat.median_ms)).c_str(), cell(ratio(a.lat.p99_ms, c.lat.p99_ms)).c_str());
    jratios["this_system/" + c.key] = rj;
  }
  // GStreamer without the cost of its two pipes (an estimate: medians subtracted).
  const auto pipes =
      std::find_if(cases.begin(), cases.end(), [](const CaseResult& c) { return c.key == "pipe_overhead"; });
  for (const auto& c : cases) {
    if (c.key.rfind("gstreamer", 0) != 0 || pipes == cases.end()) continue;
    const double net = c.lat.median_ms - pipes->lat.median_ms;
    std::printf("ratio %s/(%s-(p)) latency median %6sx   ((b) median less the pipes' median: %s ms)\n", a.tag.c_str(),
                c.tag.c_str(), cell(ratio(a.lat.median_ms, net)).c_str(), cell(net).c_str());
    jratios["this_system/" + c.key + "_less_pipes"] = Json{{"median", numberOrNull(ratio(a.lat.median_ms, net))}};
  }
  for (const auto& c : cases)
    for (const auto& n : c.notes) std::printf("  %s\n", n.c_str());
  for (const auto& c : cases)
    if (!c.error.empty()) std::printf("  %s FAILED: %s\n", c.title.c_str(), c.error.c_str());
  return Json{{"size", sizeName(sz)},
              {"load_average", {numberOrNull(load.first), numberOrNull(load.second)}},
              {"cases", jcases},
              {"ratios", jratios}};
}

// ---------------------------------------------------------------- arguments

bool parseSizes(const std::string& text, std::vector<cv::Size>& out) {
  out.clear();
  std::istringstream is(text);
  for (std::string t; std::getline(is, t, ',');) {
    int w = 0, h = 0;
    char x = 0, extra = 0;
    // Width a multiple of 8: GStreamer's I420 rows (and half rows) are then unpadded.
    if (std::sscanf(t.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || x != 'x' || w < 64 || h < 64 || w > 4096 ||
        h > 4096 || w % 8 || h % 2)
      return false;
    out.emplace_back(w, h);
  }
  return !out.empty();
}

bool parseThreads(const std::string& text, std::vector<int>& out) {
  out.clear();
  std::istringstream is(text);
  for (std::string t; std::getline(is, t, ',');) {
    if (t == "default") {
      out.push_back(-1);
      continue;
    }
    char* end = nullptr;
    const long v = std::strtol(t.c_str(), &end, 10);
    if (t.empty() || *end || v < 0 || v > 64) return false;
    out.push_back(static_cast<int>(v));
  }
  return true;
}

/// Parses argv into `o`; "" or the complaint.
std::string parseArgs(int argc, char** argv, Options& o, bool& help) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      help = true;
      return {};
    }
    if (i + 1 >= argc) return a + ": missing value (see --help)";
    const std::string v = argv[++i];
    char* end = nullptr;
    const double num = std::strtod(v.c_str(), &end);
    const bool numeric = !v.empty() && *end == 0 && std::isfinite(num);
    if (a == "--seconds" && numeric && num > 0 && num <= 3600) {
      o.seconds = num;
    } else if (a == "--warmup" && numeric && num >= 0 && num <= 60) {
      o.warmup = num;
    } else if (a == "--fps" && numeric && num > 0 && num <= 120) {
      o.fps = num;
    } else if (a == "--bitrate-kbps" && numeric && num >= 50 && num <= 50000) {
      o.bitrate_kbps = static_cast<int>(num);
    } else if (a == "--max-seconds" && numeric && num > 0) {
      o.max_seconds = num;
    } else if (a == "--port" && numeric && num >= 1 && num <= 65535) {
      o.port = static_cast<uint16_t>(num);
    } else if (a == "--sizes" && parseSizes(v, o.sizes)) {
    } else if (a == "--gst-threads" && parseThreads(v, o.gst_threads)) {
    } else if (a == "--json") {
      o.json_path = v;
    } else if (a == "--role" && (v == "sender" || v == "receiver")) {
      o.role = v;
    } else {
      return a + " " + v + ": unknown argument or bad value (see --help)";
    }
  }
  return {};
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  bool help = false;
  if (const auto why = parseArgs(argc, argv, o, help); !why.empty()) {
    std::fprintf(stderr, "bench_video: %s\n", why.c_str());
    return 2;
  }
  if (help) {
    std::fputs(kUsage, stdout);
    return 0;
  }
  try {
    if (o.role == "receiver") return receiverRole(o);
    if (o.role == "sender") return senderRole(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_video --role %s: %s\n", o.role.c_str(), e.what());
    return 1;
  }

  signal(SIGPIPE, SIG_IGN);  // a pipeline that died shows as a write error
  const std::string self = selfPath(), gst = findOnPath("gst-launch-1.0");
  Json out{{"fps", o.fps},
           {"bitrate_kbps", o.bitrate_kbps},
           {"gop", gop(o)},
           {"seconds", o.seconds},
           {"warmup_s", o.warmup},
           {"cpu_note", "CPU time / wall time over the measured window, 100 = one core; other = rest of the machine"},
           {"sizes", Json::array()}};
  bool ok = true;
  for (const cv::Size sz : o.sizes) {
    std::fprintf(stderr, "bench_video: %s ...\n", sizeName(sz).c_str());
    try {
      const double load0 = loadAverage();
      std::vector<CaseResult> cases;
      cases.push_back(runThisSystem(o, sz, self));
      for (int t : o.gst_threads) cases.push_back(runGstreamer(o, sz, gst, t));
      cases.push_back(runPipeOverhead(o, sz, gst));
      cases.push_back(runFloor(o, sz));
      for (auto& c : cases) {
        if (c.error.empty() && c.lat.frames == 0) c.error = "no picture came out in the measured window";
        ok = ok && c.error.empty();
      }
      out["sizes"].push_back(report(o, sz, cases, {load0, loadAverage()}));
    } catch (const std::exception& e) {
      std::printf("\n== %s: FAILED: %s ==\n", sizeName(sz).c_str(), e.what());
      out["sizes"].push_back(Json{{"size", sizeName(sz)}, {"error", e.what()}});
      ok = false;
    }
  }
  std::printf("\nGStreamer pipelines for %s (gst-launch-1.0 -q ...; PORT = a free UDP port):\n  send:    %s\n",
              sizeName(o.sizes.front()).c_str(), gstSender(o, o.sizes.front(), "PORT").c_str());
  for (int t : o.gst_threads) std::printf("  receive: %s\n", gstReceiver("PORT", t).c_str());
  std::printf("  pipes:   %s\n", gstPassThrough(o.sizes.front()).c_str());
  std::printf("CPU %% = CPU time / wall time over the measured window (100 = one core); CPU%% other = the rest of\n"
              "the machine meanwhile (other users: figures taken while it is high are skewed). Latency = time the\n"
              "decoded picture was in hand - capture time read from its time code.\n");
  std::fflush(stdout);
  if (!o.json_path.empty()) {
    std::ofstream f(o.json_path);
    f << out.dump(2) << "\n";
    if (!f) {
      std::fprintf(stderr, "bench_video: cannot write %s\n", o.json_path.c_str());
      return 1;
    }
  }
  return ok ? 0 : 1;
}
