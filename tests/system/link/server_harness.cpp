#include "tests/system/link/server_harness.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>

#include "inspect_robot/v1/link.pb.h"
#include "shared/record/mcap_reader.hpp"
#include "tests/support/paths.hpp"

namespace inspect::linktest {

namespace {
std::size_t countOf(const std::string& text, const std::string& needle) {
  std::size_t n = 0;
  for (std::size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + needle.size())) ++n;
  return n;
}
}  // namespace

double clockTicksPerSecond() { return static_cast<double>(::sysconf(_SC_CLK_TCK)); }

ProcSample sampleProc(pid_t pid) {
  ProcSample s;
  const std::string base = "/proc/" + std::to_string(pid);
  {
    std::ifstream f(base + "/stat");
    std::string line;
    if (!std::getline(f, line)) return s;
    // Fields after the command name, which is in parentheses and may hold spaces.
    const auto close = line.rfind(')');
    if (close == std::string::npos) return s;
    std::istringstream in(line.substr(close + 2));
    std::vector<std::string> f2;
    std::string w;
    while (in >> w) f2.push_back(w);
    // f2[0] = state (field 3); utime = field 14, stime = field 15, num_threads = field 20.
    if (f2.size() < 18) return s;
    s.cpu_ticks = std::stoull(f2[11]) + std::stoull(f2[12]);
    s.threads = std::stoull(f2[17]);
  }
  {
    std::ifstream f(base + "/status");
    std::string line;
    while (std::getline(f, line)) {
      if (line.rfind("VmRSS:", 0) == 0) s.rss_kb = std::stoull(line.substr(6));
      if (line.rfind("VmHWM:", 0) == 0) s.hwm_kb = std::stoull(line.substr(6));
    }
  }
  {
    std::ifstream f(base + "/io");
    std::string key;
    uint64_t v = 0;
    while (f >> key >> v) {
      if (key == "rchar:") s.rchar = v;
      if (key == "wchar:") s.wchar = v;
    }
  }
  s.ok = s.rss_kb > 0;
  return s;
}

ServerUnderTest::~ServerUnderTest() {
  if (proc_.running()) proc_.terminate(3.0);
  if (fifo_fd_ >= 0) ::close(fifo_fd_);
}

bool ServerUnderTest::start(const ServerStart& s) {
  dir_ = s.dir;
  runs_dir_ = dir_ + "/runs";
  fifo_ = dir_ + "/console.fifo";
  ::unlink(fifo_.c_str());
  if (::mkfifo(fifo_.c_str(), 0600) != 0) {
    error_ = "mkfifo " + fifo_ + " failed";
    return false;
  }
  // Read-write: opening does not wait for the reader, and the server never sees EOF before `quit`.
  fifo_fd_ = ::open(fifo_.c_str(), O_RDWR | O_CLOEXEC);
  if (fifo_fd_ < 0) {
    error_ = "cannot open " + fifo_;
    return false;
  }
  const std::string bin = inspect::test::binPath("pc_server");
  const std::string cfg =
      s.config_path.empty() ? inspect::test::srcPath("config/server.yaml") : s.config_path;
  std::vector<std::string> argv = {bin,       "--config",   cfg,     "--bind",      "127.0.0.1",
                                   "--port",  "0",          "--port-file", dir_ + "/port", "--no-video", "--no-foxglove",
                                   "--runs-dir", runs_dir_, "--certs", s.certs_dir};
  argv.insert(argv.end(), s.extra_args.begin(), s.extra_args.end());
  // LINK_SERVER_WRAPPER="gdb -batch -ex run -ex bt --args" (or valgrind ...) runs the server under a tool.
  if (const char* w = std::getenv("LINK_SERVER_WRAPPER"); w && *w) {
    std::istringstream ws(w);
    std::vector<std::string> pre;
    for (std::string word; ws >> word;) pre.push_back(word);
    if (!pre.empty() && pre[0].find('/') == std::string::npos) pre[0] = "/usr/bin/" + pre[0];
    argv.insert(argv.begin(), pre.begin(), pre.end());
  }
  proc_ = test::Process::spawn(argv, dir_ + "/server.out", dir_ + "/server.err", fifo_);
  if (!test::waitUntil([&] { return test::exists(dir_ + "/port") || !proc_.running(); }, 10.0) ||
      !test::exists(dir_ + "/port")) {
    error_ = "pc_server did not write its port file within 10 s:\n" + log();
    return false;
  }
  // The port file may be seen before it is written completely.
  test::waitUntil([&] { return std::atoi(test::readFile(dir_ + "/port").c_str()) > 0; }, 2.0);
  port_ = static_cast<uint16_t>(std::atoi(test::readFile(dir_ + "/port").c_str()));
  if (port_ == 0) error_ = "bad port file";
  return port_ != 0;
}

bool ServerUnderTest::console(const std::string& line) {
  if (fifo_fd_ < 0) return false;
  const std::string l = line + "\n";
  return ::write(fifo_fd_, l.data(), l.size()) == static_cast<ssize_t>(l.size());
}

std::string ServerUnderTest::out() const { return test::readFile(dir_ + "/server.out"); }
std::string ServerUnderTest::log() const { return test::readFile(dir_ + "/server.err"); }

std::size_t ServerUnderTest::countOut(const std::string& needle) const { return countOf(out(), needle); }

bool ServerUnderTest::waitOut(const std::string& needle, std::size_t count, double timeout_s) const {
  return test::waitUntil([&] { return countOf(out(), needle) >= count; }, timeout_s);
}

bool ServerUnderTest::recordStart(const std::vector<std::string>& robots, const std::string& name, double timeout_s) {
  const std::size_t before = countOf(out(), ": recording run ");
  for (const auto& r : robots) {
    console("select " + r);
    console("record start " + name);
  }
  if (!waitOut(": recording run ", before + robots.size(), timeout_s)) return false;
  const std::regex re(R"(^(\S+): recording run (\S+)$)");
  std::istringstream in(out());
  std::string line;
  while (std::getline(in, line)) {
    std::smatch m;
    if (std::regex_match(line, m, re)) run_ids_[m[1]] = m[2];
  }
  return std::all_of(robots.begin(), robots.end(), [&](const std::string& r) { return run_ids_.count(r) > 0; });
}

bool ServerUnderTest::recordStop(const std::vector<std::string>& robots, double timeout_s) {
  const std::size_t before = countOf(out(), " stopped\n");
  for (const auto& r : robots) {
    console("select " + r);
    console("record stop");
  }
  return waitOut(" stopped\n", before + robots.size(), timeout_s);
}

std::string ServerUnderTest::runId(const std::string& robot) const {
  const auto it = run_ids_.find(robot);
  return it == run_ids_.end() ? "" : it->second;
}

std::string ServerUnderTest::mcapPath(const std::string& robot) const {
  return runs_dir_ + "/" + runId(robot) + "/run.mcap";
}

std::optional<int> ServerUnderTest::quit(double timeout_s) {
  console("quit");
  if (auto st = proc_.wait(timeout_s)) return st;
  proc_.terminate(3.0);
  return std::nullopt;
}

std::vector<RecordedTelemetry> readTelemetry(const std::string& mcap_path) {
  const auto reader = record::McapReader::open(mcap_path);
  uint16_t channel = 0;
  for (const auto& [id, c] : reader.channels())
    if (c.topic.ends_with("/telemetry")) channel = id;  // "/<robot>/telemetry" (older runs: "/telemetry")
  std::vector<RecordedTelemetry> out;
  if (channel == 0) return out;
  v1::Telemetry t;
  reader.forEach([&](const record::McapMessageView& m) {
    if (m.channel_id != channel) return true;
    if (!t.ParseFromArray(m.data.data(), static_cast<int>(m.data.size())))
      throw std::runtime_error(mcap_path + ": a /telemetry message does not parse");
    out.push_back({t.serial().frames_ok(), m.publish_time_ns / 1000, m.log_time_ns});
    return true;
  });
  return out;
}

int64_t wallMinusMonoNs(int tries) {
  int64_t best_offset = 0, best_width = INT64_MAX;
  for (int i = 0; i < tries; ++i) {
    timespec a{}, w{}, b{};
    ::clock_gettime(CLOCK_MONOTONIC, &a);
    ::clock_gettime(CLOCK_REALTIME, &w);
    ::clock_gettime(CLOCK_MONOTONIC, &b);
    const int64_t an = a.tv_sec * 1'000'000'000LL + a.tv_nsec, bn = b.tv_sec * 1'000'000'000LL + b.tv_nsec;
    const int64_t wn = w.tv_sec * 1'000'000'000LL + w.tv_nsec;
    if (bn - an < best_width) {
      best_width = bn - an;
      best_offset = wn - (an + bn) / 2;
    }
  }
  return best_offset;
}

SeqCheck checkSequence(const std::vector<RecordedTelemetry>& rec, uint64_t sent) {
  SeqCheck c;
  c.sent = sent;
  c.recorded = rec.size();
  std::vector<uint8_t> seen(sent + 1, 0);
  uint64_t last = 0;
  for (const auto& r : rec) {
    if (r.seq == 0 || r.seq > sent) {
      ++c.unexpected;
      continue;
    }
    if (seen[r.seq]) ++c.duplicates;
    seen[r.seq] = 1;
    if (r.seq < last) ++c.out_of_order;
    last = r.seq;
  }
  for (uint64_t s = 1; s <= sent; ++s)
    if (!seen[s]) {
      if (c.missing == 0) c.first_missing = s;
      ++c.missing;
    }
  return c;
}

}  // namespace inspect::linktest
