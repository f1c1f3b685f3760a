// bench_video's reference cases: (b) the same frames through GStreamer, the
// cost of its two pipes alone, and (c) the in-process encode+decode floor.
#include "experiments/bench/video_bench.hpp"

namespace inspect::bench_video {
namespace {

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

}  // namespace

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

namespace {

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

}  // namespace

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

CaseResult runGstreamerRtx(const Options& o, cv::Size sz, const std::string& tool, const test::UdpRelayParams& link,
                           int latency_ms, PairRun* run) {
  CaseResult r{"gstreamer_rtx", "(b)", "(b) GStreamer rtpbin + RTX"};
  if (tool.empty()) return failed(r, "gst_rtx_pipeline was not built (libgstreamer1.0-dev missing)");
  // Three free ports: the receiver's RTP and RTCP, the sender's RTCP.
  uint16_t rtp = 0, rtcp_rx = 0, rtcp_tx = 0;
  for (int k = 0; k < 20 && (rtp == 0 || rtcp_rx == 0 || rtcp_tx == 0 || rtp == rtcp_rx || rtp == rtcp_tx ||
                             rtcp_rx == rtcp_tx);
       ++k) {
    rtp = freeUdpPort();
    rtcp_rx = freeUdpPort();
    rtcp_tx = freeUdpPort();
  }
  if (rtp == 0 || rtcp_rx == 0 || rtcp_tx == 0) return failed(r, "no three free UDP ports on 127.0.0.1");
  // One relay per direction and stream, each with the link's loss and delay (seeds apart).
  std::optional<test::UdpRelay> media, reports, feedback;
  try {
    test::UdpRelayParams p = link;
    media.emplace(rtp, p);
    p.seed = link.seed + 1000;
    reports.emplace(rtcp_rx, p);
    p.seed = link.seed + 2000;
    feedback.emplace(rtcp_tx, p);
  } catch (const std::exception& e) {
    return failed(r, e.what());
  }
  const std::string caps = "application/x-rtp,media=video,clock-rate=90000,encoding-name=H264,payload=96";
  std::ostringstream recv, send;
  recv << "rtpbin name=rtpbin latency=" << latency_ms << " do-retransmission=true rtp-profile=avpf"
       << " udpsrc port=" << rtp << " caps=" << caps << " ! rtpbin.recv_rtp_sink_0"
       << " rtpbin. ! rtph264depay request-keyframe=true ! avdec_h264 ! videoconvert ! video/x-raw,format=I420 ! fdsink fd=1 sync=false"
       << " udpsrc port=" << rtcp_rx << " ! rtpbin.recv_rtcp_sink_0"
       << " rtpbin.send_rtcp_src_0 ! udpsink host=127.0.0.1 port=" << feedback->port() << " sync=false async=false";
  const std::size_t bytes = static_cast<std::size_t>(sz.area()) * 3 / 2;
  send << "rtpbin name=rtpbin rtp-profile=avpf"
       << " fdsrc fd=0 blocksize=" << bytes << " ! rawvideoparse width=" << sz.width << " height=" << sz.height
       << " format=i420 framerate=" << fpsFraction(o.fps) << " ! x264enc tune=zerolatency speed-preset=ultrafast"
       << " bitrate=" << o.bitrate_kbps << " key-int-max=" << gop(o)
       << " ! rtph264pay config-interval=-1 pt=96 ! rtpbin.send_rtp_sink_0"
       << " rtpbin.send_rtp_src_0 ! udpsink host=127.0.0.1 port=" << media->port() << " sync=false"
       << " rtpbin.send_rtcp_src_0 ! udpsink host=127.0.0.1 port=" << reports->port() << " sync=false async=false"
       << " udpsrc port=" << rtcp_tx << " ! rtpbin.recv_rtcp_sink_0";
  r.detail = Json{{"sender_pipeline", send.str()}, {"receiver_pipeline", recv.str()}, {"latency_ms", latency_ms},
                  {"receiver_session", "rtcp-min-interval=0"}};
  Child rx, tx;
  // The receiver's NACKs go out as soon as the jitter buffer asks (AVPF early
  // feedback), not held back by the regular RTCP interval (5 s by default).
  std::vector<std::string> rargs{tool, "--receive", "--session", "rtcp-min-interval=0"}, sargs{tool, "--send"};
  for (auto& t : split(recv.str())) rargs.push_back(t);
  for (auto& t : split(send.str())) sargs.push_back(t);
  if (auto e = rx.start(rargs, false, true); !e.empty()) return failed(r, e);
  const auto until = Clock::now() + toDuration(kStartTimeoutS);
  while (!(udpPortBound(rtp) && udpPortBound(rtcp_rx)) && rx.alive() && Clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  if (!udpPortBound(rtp)) return failed(r, "the receiving pipeline did not bind its ports: " + rx.errorText());
  if (auto e = tx.start(sargs, true, false); !e.empty()) return failed(r, e);
  test::UdpRelay* m = &*media;
  FeedResult f = feedAndRead(o, sz, tx, rx,
                             {tx.cpu(), rx.cpu(), [m] { return static_cast<double>(m->counters().bytes_sent.load()); }});
  tx.stop(2);  // stdin closed: EOS, exits by itself
  rx.stop(0.5);
  if (!f.w.error.empty()) return failed(r, f.w.error);
  // The retransmission elements' counters: the last JSON line of each one's stderr.
  const auto counters = [](const Child& c) {
    std::istringstream is(c.stderrText());
    Json j = Json::object();
    for (std::string line; std::getline(is, line);)
      if (!line.empty() && line.front() == '{') j = Json::parse(line, nullptr, false);
    return j.is_discarded() ? Json::object() : j;
  };
  const Json sc = counters(tx), rc = counters(rx);
  r.lat = summarize(f.recs, f.w.t0_us, f.w.t1_us);
  r.detail["sender_rtx"] = sc;
  r.detail["receiver_rtx"] = rc;
  if (run) {
    run->recs = f.recs;
    for (auto& rec : run->recs) rec.ext_capture_us = rec.capture_us;
    run->t0_us = f.w.t0_us;
    run->t1_us = f.w.t1_us;
    run->wire_kbps = f.w.cpu_pct.at(4) / 100.0 * 8.0 / 1000.0;
    // The receiver's rtprtxreceive: requests it saw go upstream (NACKed) and RTX packets it associated (repaired).
    run->receiver = Json{{"nacked_packets", rc.value("rtx_requests", 0u)},
                         {"retransmissions", rc.value("rtx_assoc_packets", 0u)}, {"rtx", rc}};
    run->sender = Json{{"rtx", sc}};
  }
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

}  // namespace inspect::bench_video
