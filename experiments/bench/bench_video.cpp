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

#include "shared/util/cli_args.hpp"
#include "shared/util/clock.hpp"
#include "shared/video/frame_source.hpp"
#include "shared/video/h264_codec.hpp"
#include "shared/video/timecode.hpp"
#include "shared/video/video_receiver.hpp"
#include "shared/video/video_sender.hpp"

#include "experiments/bench/video_bench.hpp"

namespace inspect::bench_video {
namespace {

constexpr const char* kUsage =
    "usage: bench_video [--seconds N] [--sizes WxH,...] [--fps F] [--bitrate-kbps K]\n"
    "                   [--warmup S] [--gst-threads LIST] [--json FILE]\n"
    "       bench_video --loss [--loss-pcts LIST] [--delays-ms LIST] [--no-burst] [--seed N]\n"
    "                   [--intra-refresh] [--adapt 0|1] [--systems a,a0,b] [--gst-latency-ms N] [same options]\n"
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
    "--loss: the loss sweep instead (docs/video.md): (a) and (a0) (repair off, keyframe requests only)\n"
    "through a seeded UDP relay, both ways, at each --loss-pcts (default 0,1,5,10,20) and a burst case\n"
    "(--no-burst: without), at each --delays-ms one way (default 10,50); --seed N; first size only;\n"
    "--intra-refresh: libx264's periodic intra refresh instead of an IDR every second; --adapt 0: the\n"
    "sender's rate adaptation off (default on); --systems: which of (a), (a0), (b) run (default all;\n"
    "(b) = GStreamer rtpbin + rtprtxsend/rtprtxreceive through gst_rtx_pipeline, built beside this;\n"
    "its jitter buffer latency --gst-latency-ms, default 2 RTT + 30 ms).\n"
    "Internal: --role sender|receiver [--port P] [--max-seconds S] [--nack 0|1]: the two processes of (a).\n";

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
  VideoReceiver rx(ReceiverSettings{.bind = "127.0.0.1", .port = 0, .nack = o.nack});
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
                 {"decode_errors", st->decode_errors}, {"late", st->late}, {"packets", st->packets},
                 {"keyframe_requests", st->keyframe_requests}, {"nacks_sent", st->nacks_sent},
                 {"nacked_packets", st->nacked_packets}, {"retransmissions", st->retransmissions},
                 {"rtx_unneeded", st->rtx_unneeded}, {"tail_probes", st->tail_probes}, {"plis_sent", st->plis_sent}, {"rtt_ms", st->rtt_ms}};
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
  s.adapt.enabled = o.adapt;
  VideoSender tx(s);
  tx.start();
  waitForStdinEof(o.max_seconds);
  const SenderStats st = tx.stats();
  tx.stop();
  printLine(Json{{"encoder", st.encoder}, {"captured", st.captured}, {"encoded", st.encoded}, {"dropped", st.dropped},
                 {"keyframes", st.keyframes}, {"packets", st.packets}, {"bytes", st.bytes},
                 {"send_errors", st.send_errors}, {"encode_ms", st.encode_ms}, {"nacked_packets", st.nacked_packets},
                 {"retransmitted", st.retransmitted}, {"not_in_history", st.not_in_history},
                 {"repeat_nacks", st.repeat_nacks}, {"plis", st.plis}, {"rate_kbps", st.rate_kbps},
                 {"rate_level", st.rate_level}, {"rate_changes", st.rate_changes}, {"rate_reason", st.rate_reason},
                 {"rate_skipped", st.rate_skipped}, {"peer_loss_pct", st.peer_loss_pct}, {"error", st.error}});
  return 0;
}

/// The common arguments of a role process.
std::vector<std::string> roleArgs(const std::string& self, const std::string& role, const Options& o, cv::Size sz) {
  std::vector<std::string> args{self, "--role", role, "--sizes", sizeName(sz), "--fps", std::to_string(o.fps),
                                "--bitrate-kbps", std::to_string(o.bitrate_kbps), "--max-seconds",
                                std::to_string(o.warmup + o.seconds + 60), "--adapt", o.adapt ? "1" : "0"};
  if (o.intra_refresh) args.push_back("--intra-refresh");
  return args;
}

}  // namespace

CaseResult runThisSystem(const Options& o, cv::Size sz, const std::string& self, const RelayCase* relay,
                         PairRun* run) {
  CaseResult r{"this_system", "(a)", "(a) this system"};
  Child rx, tx;
  std::string rx_pending, tx_pending, line;
  auto rx_args = roleArgs(self, "receiver", o, sz);
  if (relay) rx_args.insert(rx_args.end(), {"--nack", relay->nack ? "1" : "0"});
  if (auto e = rx.start(rx_args, true, true); !e.empty()) return failed(r, e);
  if (!readLine(rx.out(), rx_pending, line, Clock::now() + toDuration(kStartTimeoutS)))
    return failed(r, "receiver did not start: " + rx.errorText());
  uint16_t port = 0;
  try {
    port = Json::parse(line).at("port").get<uint16_t>();
  } catch (const nlohmann::json::exception& e) {
    return failed(r, "receiver said '" + line + "': " + e.what());
  }
  // The lossy link: a seeded UdpRelay in this process, both ways.
  std::optional<test::UdpRelay> link;
  if (relay) {
    try {
      link.emplace(port, relay->link);
    } catch (const std::exception& e) {
      return failed(r, e.what());
    }
    port = link->port();
  }
  auto args = roleArgs(self, "sender", o, sz);
  args.insert(args.end(), {"--port", std::to_string(port)});
  if (auto e = tx.start(args, true, true); !e.empty()) return failed(r, e);
  // The relay's forwarded bytes ride on the probes (the window's rate of a probe x 100).
  std::vector<std::function<double()>> probes{tx.cpu(), rx.cpu()};
  if (link) probes.push_back([&link] { return static_cast<double>(link->counters().bytes_sent.load()); });
  const Window w = measureWindow(o, {&rx, &tx}, probes);
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
  if (run) {
    run->recs = recs;
    run->t0_us = w.t0_us;
    run->t1_us = w.t1_us;
    if (link) run->wire_kbps = w.cpu_pct.at(2) / 100.0 * 8.0 / 1000.0;
    run->receiver = receiver["stats"];
    run->sender = sender;
  }
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

namespace {

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

/// --sizes WxH,...: width a multiple of 8 (GStreamer's I420 rows and half rows are then unpadded).
std::vector<cv::Size> parseSizes(cli::ArgReader& a) {
  std::vector<cv::Size> out;
  for (const auto& t : a.list()) {
    int w = 0, h = 0;
    char x = 0, extra = 0;
    if (std::sscanf(t.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || x != 'x' || w < 64 || h < 64 || w > 4096 ||
        h > 4096 || w % 8 || h % 2)
      a.fail("'" + t + "' is not WxH with W a multiple of 8 in [64, 4096] and H even in [64, 4096]");
    out.emplace_back(w, h);
  }
  return out;
}

/// --gst-threads N,...: each 0-64 or "default" (-1).
std::vector<int> parseThreads(cli::ArgReader& a) {
  std::vector<int> out;
  for (const auto& t : a.list()) {
    char* end = nullptr;
    const long v = std::strtol(t.c_str(), &end, 10);
    if (t == "default") out.push_back(-1);
    else if (t.empty() || *end || v < 0 || v > 64) a.fail("'" + t + "' is not 0-64 or default");
    else out.push_back(static_cast<int>(v));
  }
  return out;
}

/// --systems a,a0,b: a non-empty subset, in the order given.
std::vector<std::string> parseSystems(cli::ArgReader& a) {
  std::vector<std::string> out;
  for (const auto& t : a.list()) {
    if (t != "a" && t != "a0" && t != "b") a.fail("'" + t + "' is not a, a0 or b");
    out.push_back(t);
  }
  if (out.empty()) a.fail("no system");
  return out;
}

/// A comma-separated list of numbers in [lo, hi].
std::vector<double> parseNumbers(cli::ArgReader& a, double lo, double hi) {
  std::vector<double> out;
  for (const auto& t : a.list()) {
    char* end = nullptr;
    const double v = std::strtod(t.c_str(), &end);
    if (t.empty() || *end || !std::isfinite(v) || v < lo || v > hi)
      a.fail("'" + t + "' is not a number in [" + cell(lo, "%g") + ", " + cell(hi, "%g") + "]");
    out.push_back(v);
  }
  return out;
}

void parseArgs(int argc, char** argv, Options& o) {
  cli::readOrExit("bench_video", argc, argv, [&](cli::ArgReader& a) {
    if (a.isHelp()) {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else if (a.is("--seconds")) o.seconds = a.numberAbove(0, 3600);
    else if (a.is("--warmup")) o.warmup = a.number(0, 60);
    else if (a.is("--fps")) o.fps = a.numberAbove(0, 120);
    else if (a.is("--bitrate-kbps")) o.bitrate_kbps = static_cast<int>(a.integer(50, 50000));
    else if (a.is("--max-seconds")) o.max_seconds = a.numberAbove(0);
    else if (a.is("--port")) o.port = static_cast<uint16_t>(a.integer(1, 65535));
    else if (a.is("--sizes")) o.sizes = parseSizes(a);
    else if (a.is("--gst-threads")) o.gst_threads = parseThreads(a);
    else if (a.is("--json")) o.json_path = a.path();
    else if (a.is("--role")) o.role = a.choice({"sender", "receiver"});
    else if (a.is("--nack")) o.nack = a.integer(0, 1) == 1;
    else if (a.is("--loss")) o.loss = true;
    else if (a.is("--loss-pcts")) o.loss_pcts = parseNumbers(a, 0, 100);
    else if (a.is("--delays-ms")) o.delays_ms = parseNumbers(a, 0, 1000);
    else if (a.is("--no-burst")) o.burst = false;
    else if (a.is("--intra-refresh")) o.intra_refresh = true;
    else if (a.is("--systems")) o.systems = parseSystems(a);
    else if (a.is("--gst-latency-ms")) o.gst_latency_ms = static_cast<int>(a.integer(1, 10000));
    else if (a.is("--adapt")) o.adapt = a.integer(0, 1) == 1;
    else if (a.is("--seed")) o.seed = static_cast<uint32_t>(a.unsignedInteger(UINT32_MAX));
    else a.unknown();
  });
}

/// Writes `out` to --json when asked; the exit status.
int finish(const Options& o, const Json& out, bool ok) {
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

}  // namespace
}  // namespace inspect::bench_video

int main(int argc, char** argv) {
  using namespace inspect::bench_video;
  Options o;
  parseArgs(argc, argv, o);
  try {
    if (o.role == "receiver") return receiverRole(o);
    if (o.role == "sender") return senderRole(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_video --role %s: %s\n", o.role.c_str(), e.what());
    return 1;
  }

  signal(SIGPIPE, SIG_IGN);  // a pipeline that died shows as a write error
  const std::string self = selfPath(), gst = findOnPath("gst-launch-1.0");
  if (o.loss) {
    Json out;
    const bool ok = runLossSweep(o, self, out);
    return finish(o, out, ok);
  }
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
  return finish(o, out, ok);
}
