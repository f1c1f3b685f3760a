// bench_video's shared parts: latency figures, CPU time, child-process I/O,
// the measured window (video_bench.hpp).
#include "experiments/bench/video_bench.hpp"

namespace inspect::bench_video {

/// The encoder of (a) and (c): the library's defaults (libx264 ultrafast
/// zerolatency, one thread) with this run's size, rate, bitrate and GOP.
EncoderSettings encoderSettings(const Options& o, cv::Size sz) {
  EncoderSettings es;
  es.width = sz.width;
  es.height = sz.height;
  es.fps = o.fps;
  es.bitrate_kbps = o.bitrate_kbps;
  es.gop = gop(o);
  es.intra_refresh = o.intra_refresh;
  return es;
}

Clock::duration toDuration(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

/// `v` printed with `fmt`, "-" when not a number.
std::string cell(double v, const char* fmt) {
  if (!std::isfinite(v)) return "-";
  char b[32];
  std::snprintf(b, sizeof b, fmt, v);
  return b;
}

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
Latency summarize(const std::vector<FrameRecord>& recs, uint64_t t0, uint64_t t1, bool ext) {
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

CaseResult failed(CaseResult r, const std::string& why) {
  r.error = why;
  return r;
}


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

/// Waits out the warm-up from now, then the measured window, sampling the CPU
/// probes at both ends; stops early when one of `kids` exits or `check`
/// returns an error.
Window measureWindow(const Options& o, const std::vector<Child*>& kids,
                     const std::vector<std::function<double()>>& probes,
                     const std::function<std::string()>& check) {
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

}  // namespace inspect::bench_video
