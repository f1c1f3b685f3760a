// bench_video --loss: the video path on a lossy link (issue 39, docs/video.md).
// (a) this system with NACK + RTX repair and (a0) the same with repair off
// (keyframe requests over RTCP only), each through the project's seeded UDP
// relay (tests/support/udp_relay: loss both ways, so feedback is lost too, and
// a fixed one-way delay), per one-way delay and loss level, plus a burst case.
// Figures per run, over the measured window:
//   clean %     pictures shown / frames captured (fps x window); a picture is shown only when
//               the decoder gave it whole (no concealment: H264Decoder refuses those) and no
//               loss before it awaits a keyframe; its capture time is the RTP extension's
//   clean fps   pictures shown per second (adaptation may halve the frame rate)
//   freeze      time between consecutive shown pictures minus the frame interval: p50/p99/max
//   g2g         glass-to-glass latency (capture time from the picture's time code): p50/p99
//   wire        bytes the relay forwarded to the receiver, kbit/s
//   repair      packets NACKed (each try), retransmissions that filled a hole, keyframe requests
//   rate        the sender's bitrate and level at the end (rate adaptation), and how often it changed
//   damaged     pictures shown whose time code reads another capture time than the packet's
//               (a damaged picture that the checks let through; must stay 0)
//   coarse      pictures shown whose time code could not be read: at a low bitrate (rate
//               adaptation) the encoder blurs it; shown, not counted as damaged
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "experiments/bench/video_bench.hpp"

namespace inspect::bench_video {
namespace {

// The burst case: for 200 ms of every 2 s, 30 % of the datagrams (both ways) are lost.
constexpr double kBurstEveryMs = 2000, kBurstMs = 200, kBurstDrop = 0.30;

struct LossRow {
  double delay_ms = 0;
  std::string loss;  // "10 %", "burst"
  std::string system;
  double clean_pct = NAN, clean_fps = NAN, freeze_p50 = NAN, freeze_p99 = NAN, freeze_max = NAN;
  double g2g_p50 = NAN, g2g_p99 = NAN, wire_kbps = NAN;
  uint64_t shown = 0, expected = 0, damaged = 0, coarse = 0;
  uint64_t nacked = 0, repaired = 0, keyframe_requests = 0, lost_packets = 0;
  int rate_kbps = 0, rate_level = 0;
  uint64_t rate_changes = 0;
  std::string error;
  Json receiver = Json::object(), sender = Json::object();  // the two processes' counters
};

/// The row's figures from one run's pictures, captured in [t0, t1).
void figures(const Options& o, const PairRun& run, uint64_t t0, uint64_t t1, LossRow& row) {
  std::vector<uint64_t> arrivals;
  std::vector<double> g2g_ms;
  for (const auto& r : run.recs) {
    if (r.ext_capture_us == 0) {  // (b): no capture time but the time code's
      if (r.arrive_us >= t0 && r.arrive_us < t1) ++row.coarse;
      continue;
    }
    if (r.ext_capture_us < t0 || r.ext_capture_us >= t1) continue;
    arrivals.push_back(r.arrive_us);
    g2g_ms.push_back(static_cast<double>(static_cast<int64_t>(r.arrive_us - r.ext_capture_us)) / 1000.0);
    if (r.capture_us == 0)
      ++row.coarse;
    else if (std::llabs(static_cast<long long>(r.capture_us - r.ext_capture_us)) > 1000)
      ++row.damaged;
  }
  std::sort(arrivals.begin(), arrivals.end());
  row.shown = arrivals.size();
  row.expected = static_cast<uint64_t>(std::llround(static_cast<double>(t1 - t0) / 1e6 * o.fps));
  row.clean_pct = row.expected ? 100.0 * std::min<double>(1.0, static_cast<double>(row.shown) / row.expected) : NAN;
  row.clean_fps = static_cast<double>(row.shown) / (static_cast<double>(t1 - t0) / 1e6);
  const double interval_ms = 1000.0 / o.fps;
  std::vector<double> freezes;
  for (std::size_t i = 1; i < arrivals.size(); ++i)
    freezes.push_back(std::max(0.0, static_cast<double>(arrivals[i] - arrivals[i - 1]) / 1000.0 - interval_ms));
  if (!freezes.empty()) {
    row.freeze_p50 = percentile(freezes, 0.5);
    row.freeze_p99 = percentile(freezes, 0.99);
    row.freeze_max = *std::max_element(freezes.begin(), freezes.end());
  }
  if (!g2g_ms.empty()) {
    row.g2g_p50 = percentile(g2g_ms, 0.5);
    row.g2g_p99 = percentile(g2g_ms, 0.99);
  }
  row.wire_kbps = run.wire_kbps;
  const Json& rx = run.receiver;
  row.nacked = rx.value("nacked_packets", 0ull);
  row.repaired = rx.value("retransmissions", 0ull);
  row.keyframe_requests = rx.value("keyframe_requests", 0ull);
  row.lost_packets = rx.value("lost_packets", 0ull);
  row.rate_kbps = run.sender.value("rate_kbps", 0);
  row.rate_level = run.sender.value("rate_level", 0);
  row.rate_changes = run.sender.value("rate_changes", 0ull);
  row.receiver = run.receiver;
  row.sender = run.sender;
}

Json toJson(const LossRow& r) {
  return Json{{"delay_ms", r.delay_ms},
              {"loss", r.loss},
              {"system", r.system},
              {"clean_pct", numberOrNull(r.clean_pct)},
              {"clean_fps", numberOrNull(r.clean_fps)},
              {"shown", r.shown},
              {"expected", r.expected},
              {"freeze_ms", {{"p50", numberOrNull(r.freeze_p50)}, {"p99", numberOrNull(r.freeze_p99)},
                             {"max", numberOrNull(r.freeze_max)}}},
              {"g2g_ms", {{"p50", numberOrNull(r.g2g_p50)}, {"p99", numberOrNull(r.g2g_p99)}}},
              {"wire_kbps", numberOrNull(r.wire_kbps)},
              {"nacked_packets", r.nacked},
              {"retransmissions", r.repaired},
              {"keyframe_requests", r.keyframe_requests},
              {"lost_packets_unrepaired", r.lost_packets},
              {"damaged_shown", r.damaged},
              {"coarse_shown", r.coarse},
              {"rate_end_kbps", r.rate_kbps},
              {"rate_end_level", r.rate_level},
              {"rate_changes", r.rate_changes},
              {"receiver", r.receiver},
              {"sender", r.sender},
              {"error", r.error.empty() ? Json(nullptr) : Json(r.error)}};
}

void printRow(const LossRow& r) {
  std::printf("| %5.0f | %-6s | %-4s | %6s | %5s | %5s / %6s / %6s | %6s / %6s | %6s | %6llu / %6llu / %4llu | %4llu | %llu / %llu | %5d / %d / %3llu |%s\n",
              r.delay_ms, r.loss.c_str(), r.system.c_str(), cell(r.clean_pct, "%.1f").c_str(), cell(r.clean_fps, "%.1f").c_str(),
              cell(r.freeze_p50, "%.0f").c_str(), cell(r.freeze_p99, "%.0f").c_str(), cell(r.freeze_max, "%.0f").c_str(),
              cell(r.g2g_p50, "%.1f").c_str(), cell(r.g2g_p99, "%.1f").c_str(), cell(r.wire_kbps, "%.0f").c_str(),
              static_cast<unsigned long long>(r.nacked), static_cast<unsigned long long>(r.repaired),
              static_cast<unsigned long long>(r.keyframe_requests), static_cast<unsigned long long>(r.lost_packets),
              static_cast<unsigned long long>(r.damaged), static_cast<unsigned long long>(r.coarse), r.rate_kbps, r.rate_level,
              static_cast<unsigned long long>(r.rate_changes), r.error.empty() ? "" : (" FAILED: " + r.error).c_str());
  std::fflush(stdout);
}

int gstLatencyMs(double one_way_ms) { return static_cast<int>(std::lround(4 * one_way_ms + 30)); }

/// `name` in the directory of `self` when it is an executable there, else "".
std::string besideSelf(const std::string& self, const std::string& name) {
  const auto slash = self.rfind('/');
  const std::string p = (slash == std::string::npos ? std::string(".") : self.substr(0, slash)) + "/" + name;
  return access(p.c_str(), X_OK) == 0 ? p : std::string();
}

}  // namespace

bool runLossSweep(const Options& o, const std::string& self, Json& out) {
  const cv::Size sz = o.sizes.at(0);
  const std::string gst_tool = besideSelf(self, "gst_rtx_pipeline");
  std::printf("bench_video --loss: %s @ %g fps, %d kbit/s, GOP %d%s, rate adaptation %s; %g s measured after %g s "
              "warm-up per run; seed %u; relay loss both ways; burst = %g %% for %g ms of every %g s\n\n",
              sizeName(sz).c_str(), o.fps, o.bitrate_kbps, gop(o), o.intra_refresh ? " (intra refresh)" : "",
              o.adapt ? "on" : "off", o.seconds, o.warmup, o.seed, kBurstDrop * 100,
              kBurstMs, kBurstEveryMs / 1000);
  std::printf("| delay ms | loss | sys | clean %% | clean fps | freeze p50 / p99 / max ms | g2g p50 / p99 ms | wire kbit/s | "
              "NACKed / repaired / keyframe req | lost | damaged / coarse shown | rate kbit/s / level / changes |\n"
              "|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  std::fflush(stdout);
  struct Level {
    std::string name;
    double drop, burst_drop;
  };
  std::vector<Level> levels;
  for (double p : o.loss_pcts) levels.push_back({cell(p, "%g") + " %", p / 100.0, 0});
  if (o.burst) levels.push_back({"burst", 0, kBurstDrop});
  Json rows = Json::array();
  bool ok = true;
  for (double delay : o.delays_ms)
    for (const auto& lv : levels)
      for (const std::string& name : o.systems) {
        const std::string sys = "(" + name + ")";
        const bool nack = sys == "(a)";
        RelayCase rc;
        rc.link.drop = lv.drop;
        rc.link.delay_ms = delay;
        if (lv.burst_drop > 0) {
          rc.link.burst_every_ms = kBurstEveryMs;
          rc.link.burst_ms = kBurstMs;
          rc.link.burst_drop = lv.burst_drop;
        }
        rc.link.seed = o.seed;
        rc.nack = nack;
        LossRow row;
        row.delay_ms = delay;
        row.loss = lv.name;
        row.system = sys;
        std::fprintf(stderr, "bench_video --loss: %g ms, %s, %s ...\n", delay, lv.name.c_str(), row.system.c_str());
        PairRun run;
        // (b)'s jitter buffer waits 2 RTT + 30 ms: room for one retransmission and a retry.
        const int latency = o.gst_latency_ms > 0 ? o.gst_latency_ms : gstLatencyMs(delay);
        const CaseResult c = sys == "(b)" ? runGstreamerRtx(o, sz, gst_tool, rc.link, latency, &run)
                                          : runThisSystem(o, sz, self, &rc, &run);
        if (!c.error.empty()) {
          row.error = c.error;
          ok = false;
        } else {
          figures(o, run, run.t0_us, run.t1_us, row);
          // A run fails when its pipeline gave nothing at all. No clean picture among those that
          // came out is a figure (0 % clean: the reference (b) at 320x240 over 3 s sometimes
          // is), not a broken run.
          if (row.shown + row.coarse == 0) {
            row.error = "no picture came out in the measured window";
            ok = false;
          } else if (row.damaged > 0) {
            row.error = std::to_string(row.damaged) + " damaged pictures shown";
            ok = false;
          }
        }
        printRow(row);
        rows.push_back(toJson(row));
      }
  std::printf("\n(a) = NACK + RTX repair + rate adaptation; (a0) = repair off, keyframe requests (RTCP PLI) only;\n"
              "(b) = GStreamer: x264enc (same settings) ! rtph264pay ! rtpbin + rtprtxsend -> rtpbin with\n"
              "rtprtxreceive (do-retransmission, AVPF, jitter buffer latency 2 RTT + 30 ms or --gst-latency-ms)\n"
              "! rtph264depay request-keyframe=true ! avdec_h264; RTP and both RTCP directions through relays\n"
              "with the same loss and delay. (b)'s pictures count when their time code reads: a concealed\n"
              "picture whose time code survived counts as clean ((b)'s damage is not measured; its 'coarse'\n"
              "are pictures too damaged to read). lost = packets never repaired (the receiver's depacketizer\n"
              "saw them missing). Targets (issue 39) at 10 %% loss, 10 ms one way: clean >= 97 %%, freeze\n"
              "p99 < 150 ms, g2g p99 < 2 RTT + 50 ms = 90 ms.\n");
  out = Json{{"size", sizeName(sz)},   {"fps", o.fps},         {"bitrate_kbps", o.bitrate_kbps},
             {"intra_refresh", o.intra_refresh}, {"adapt", o.adapt},
             {"gst_latency_ms", o.gst_latency_ms > 0 ? Json(o.gst_latency_ms) : Json("2 RTT + 30 ms")},
             {"gop", gop(o)},          {"seconds", o.seconds}, {"warmup_s", o.warmup},
             {"seed", o.seed},         {"burst", {{"every_ms", kBurstEveryMs}, {"ms", kBurstMs}, {"drop", kBurstDrop}}},
             {"rows", rows}};
  return ok;
}

}  // namespace inspect::bench_video
