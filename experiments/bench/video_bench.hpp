#pragma once
// bench_video's parts (experiments/bench): options, latency figures, CPU
// time, child processes, the measured window; bench_video.cpp runs the cases.
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
#include "tests/support/udp_relay.hpp"

namespace inspect::bench_video {

using Clock = std::chrono::steady_clock;
using Json = nlohmann::ordered_json;
using namespace inspect::video;

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
  // --loss: the loss sweep (video_loss.cpp) instead of the latency comparison
  bool loss = false;
  std::vector<double> loss_pcts{0, 1, 5, 10, 20};  // random loss both ways, %
  bool burst = true;                               // and the burst case (kBurst*)
  std::vector<double> delays_ms{10, 50};           // one-way delay
  uint32_t seed = 1;
  bool intra_refresh = false;  // libx264 periodic intra refresh instead of IDRs every GOP
  bool adapt = true;           // (a): rate adaptation on the sender
  std::vector<std::string> systems{"a", "a0", "b"};  // --loss: which systems run
  int gst_latency_ms = 0;      // (b)'s jitter buffer latency; 0 = 2 RTT + 30 ms
  // --role
  bool nack = true;  // receiver: NACK + RTX repair (off: keyframe requests only)
  std::string role;
  uint16_t port = 0;
  double max_seconds = 120;  // a role process ends by itself after this
};

inline int gop(const Options& o) { return std::max(1, static_cast<int>(std::lround(o.fps))); }

/// The encoder of (a) and (c): the library's defaults (libx264 ultrafast
/// zerolatency, one thread) with this run's size, rate, bitrate and GOP.
EncoderSettings encoderSettings(const Options& o, cv::Size sz);

inline std::string sizeName(cv::Size s) { return std::to_string(s.width) + "x" + std::to_string(s.height); }
inline double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
Clock::duration toDuration(double s);

inline Json numberOrNull(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }
/// `v` printed with `fmt`, "-" when not a number.
std::string cell(double v, const char* fmt = "%.2f");

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

double percentile(std::vector<double> v, double q);

Latency fromSamples(const std::vector<double>& ms);

/// Latency of the pictures captured in [t0, t1): arrival - capture, where the
/// capture time is the picture's time code, or the RTP extension when `ext`.
Latency summarize(const std::vector<FrameRecord>& recs, uint64_t t0, uint64_t t1, bool ext = false);

Json toJson(const Latency& l);

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

CaseResult failed(CaseResult r, const std::string& why);

inline double timespecSeconds(const timespec& ts) { return static_cast<double>(ts.tv_sec) + ts.tv_nsec * 1e-9; }

/// utime + stime of a process (all its threads) in seconds; NAN when unreadable.
double processCpuSeconds(pid_t pid);

std::function<double()> threadCpu(std::thread& t);

double processCpuSelf();

/// CPU seconds all cores of the machine have been busy (/proc/stat); NAN when unreadable.
double machineBusySeconds();

/// CPU % (of one core) the rest of the machine used between two samples of
/// (machine busy, ours) seconds over `wall_s`.
double otherPct(double machine0, double machine1, double ours0, double ours1, double wall_s);

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

  /// All it wrote on stderr so far (or before it was stopped).
  std::string stderrText() const { return err_ >= 0 ? readErr() : stderr_text_; }

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
bool readFully(int fd, uint8_t* buf, std::size_t n, const std::function<bool()>& stop);

/// One line from `fd` (without the newline), by `deadline`; false on EOF or time out.
bool readLine(int fd, std::string& pending, std::string& line, Clock::time_point deadline);

/// Writes all of `data` to the non-blocking `fd`; false when it fails or takes
/// more than kWriteTimeoutS.
bool writeAll(int fd, const uint8_t* data, std::size_t n, std::string& error);

std::string selfPath();

/// `prog` looked up on PATH; "" when absent.
std::string findOnPath(const std::string& prog);

/// A UDP port that was free a moment ago on 127.0.0.1 (0 when none).
uint16_t freeUdpPort();

/// True once some socket is bound to UDP `port` (IPv4, /proc/net/udp).
bool udpPortBound(uint16_t port);

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
                     const std::function<std::string()>& check = {});

/// gst-launch-1.0 pipelines of (b): the sender of `o` at size `sz` to UDP
/// `port`, the receiver with avdec_h264 `threads` (-1: its default), and the
/// pass-through of the pipe cost (p).
std::string gstSender(const Options& o, cv::Size sz, const std::string& port);
std::string gstReceiver(const std::string& port, int threads);
std::string gstPassThrough(cv::Size sz);

/// (a) this system in two processes; through `relay` when given (a seeded
/// UdpRelay with its link's parameters, the receiver's NACK repair on or
/// off). What the run saw goes to `run` when not null: its pictures (time
/// code read), the window, the relay's delivered rate, both processes' counters.
struct RelayCase {
  test::UdpRelayParams link;
  bool nack = true;
};
struct PairRun {
  std::vector<FrameRecord> recs;
  uint64_t t0_us = 0, t1_us = 0;  // the measured window
  double wire_kbps = NAN;
  Json receiver = Json::object(), sender = Json::object();
};
CaseResult runThisSystem(const Options& o, cv::Size sz, const std::string& self, const RelayCase* relay = nullptr,
                         PairRun* run = nullptr);

/// --loss: the sweep over loss and delay; prints its tables, fills `out`; false when a case failed.
bool runLossSweep(const Options& o, const std::string& self, Json& out);

/// (b) the frames through GStreamer (gst-launch-1.0 at `gst`), avdec_h264
/// with `threads` (-1: its default).
CaseResult runGstreamer(const Options& o, cv::Size sz, const std::string& gst, int threads);
/// (b) of the loss sweep: the frames through GStreamer with retransmission
/// (gst_rtx_pipeline at `tool`: rtpbin + rtprtxsend / rtprtxreceive, the
/// jitter buffer's do-retransmission, AVPF), RTP and both RTCP directions
/// each through a seeded UdpRelay with `link`'s loss and delay; the jitter
/// buffer's latency `latency_ms`. Fills `run` like runThisSystem (capture
/// times from the time code; ext_capture_us = capture_us when readable).
CaseResult runGstreamerRtx(const Options& o, cv::Size sz, const std::string& tool, const test::UdpRelayParams& link,
                           int latency_ms, PairRun* run);
/// (p) the cost of (b)'s two pipes alone.
CaseResult runPipeOverhead(const Options& o, cv::Size sz, const std::string& gst);
/// (c) the in-process encode+decode floor.
CaseResult runFloor(const Options& o, cv::Size sz);

}  // namespace inspect::bench_video
