#include "shared/video/video_sender.hpp"

#include <chrono>
#include <random>

#include <opencv2/imgproc.hpp>

#include <poll.h>
#include <pthread.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/udp.hpp>

#include "shared/util/clock.hpp"
#include "shared/util/log.hpp"
#include "shared/video/rtcp.hpp"
#include "shared/video/rtp_h264.hpp"
#include "shared/video/rtx.hpp"

namespace inspect::video {

namespace asio = boost::asio;
using Clock = std::chrono::steady_clock;

namespace {
// IPv4 + UDP headers, the RTP header and the capture-time extension on a
// frame's first packet (docs/video.md).
constexpr std::size_t kOverhead = 28 + kRtpHeaderSize + 16;
// A NACK of a packet retransmitted less than this ago is the receiver's
// second copy of the same NACK (VideoReceiver sends each twice): not answered.
// Its retries come at least 10 ms apart (NackSettings::min_retry_us).
constexpr uint64_t kRepeatNackUs = 5000;

EncoderSettings effectiveEncoder(const SenderSettings& s) {
  EncoderSettings e = s.encoder;
  e.width = s.source.width;
  e.height = s.source.height;
  e.fps = s.source.fps;
  return e;
}

// What the encoder does at the rate controller's state: its bitrate, and
// at a reduced level half the frame rate and half the size (even, >= 64).
EncoderSettings adaptedEncoder(const SenderSettings& s, const RateState& r) {
  EncoderSettings e = effectiveEncoder(s);
  e.bitrate_kbps = r.kbps;
  e.fps /= RateController::fpsDivisor(r.level);
  const int d = RateController::sizeDivisor(r.level);
  if (d > 1) {
    e.width = std::max(64, e.width / d / 2 * 2);
    e.height = std::max(64, e.height / d / 2 * 2);
  }
  return e;
}

RateSettings rateSettings(const SenderSettings& s) {
  RateSettings r = s.adapt;
  r.start_kbps = s.encoder.bitrate_kbps;
  // The range always holds the configured rate; max 0 = the configured rate.
  r.max_kbps = r.max_kbps == 0 ? r.start_kbps : std::max(r.max_kbps, r.start_kbps);
  r.min_kbps = std::min(r.min_kbps, r.start_kbps);
  r.enabled = r.enabled && s.retransmission;  // the reports come on the RTCP path
  return r;
}

uint32_t randomSsrc() {
  std::random_device rd;
  uint32_t v = 0;
  while (v == 0) v = rd();
  return v;
}
}  // namespace

std::string validate(const SenderSettings& s) {
  // Capture only: the source's size and rate (checked as the encoder's).
  if (!s.stream) return validate(effectiveEncoder(s));
  if (s.mtu < 256 || s.mtu > 9000) return "video.mtu: " + std::to_string(s.mtu) + " out of range [256, 9000]";
  if (s.port == 0) return "video.port: 0 is not a destination port";
  if (s.host.empty()) return "video.host: empty";
  if (s.history_packets > 65536)
    return "video.history_packets: " + std::to_string(s.history_packets) + " out of range [0, 65536]";
  if (!(s.history_s >= 0.01 && s.history_s <= 10))
    return "video.history_s: " + std::to_string(s.history_s) + " out of range [0.01, 10]";
  if (s.adapt.enabled && s.retransmission)
    if (auto why = validate(rateSettings(s)); !why.empty()) return why;
  return validate(effectiveEncoder(s));
}

struct VideoSender::Net {
  asio::io_context io;
  asio::ip::udp::socket socket{io};
  asio::ip::udp::endpoint dest;
  std::mutex send_mu;  // the encode and feedback threads both send on `socket`
  std::mutex history_mu;
  RetransmissionHistory history{0, 0};
  uint16_t rtx_seq = 0;
  uint32_t last_rtp_ts = 0;                 // of the last frame sent (guarded by history_mu)
  uint32_t packets_sent = 0, octets_sent = 0;  // for the SR (guarded by history_mu)

  bool send(std::span<const uint8_t> d, std::string* error) {
    std::lock_guard lk(send_mu);
    boost::system::error_code ec;
    socket.send_to(asio::buffer(d.data(), d.size()), dest, 0, ec);
    if (ec && error)
      *error = "video: send to " + dest.address().to_string() + ":" + std::to_string(dest.port()) + ": " + ec.message();
    return !ec;
  }
};

VideoSender::VideoSender(SenderSettings s) : s_(std::move(s)), net_(std::make_unique<Net>()) {
  if (auto why = validate(s_); !why.empty()) throw VideoError(why);
  ssrc_ = s_.ssrc ? s_.ssrc : randomSsrc();
  do rtx_ssrc_ = randomSsrc();
  while (rtx_ssrc_ == ssrc_);
  if (!s_.stream) return;  // capture only: no destination, no socket
  net_->history = RetransmissionHistory(s_.retransmission ? s_.history_packets : 0,
                                        static_cast<uint64_t>(s_.history_s * 1e6));
  net_->rtx_seq = static_cast<uint16_t>(rtx_ssrc_);
  boost::system::error_code ec;
  asio::ip::udp::resolver resolver(net_->io);
  auto results = resolver.resolve(asio::ip::udp::v4(), s_.host, std::to_string(s_.port), ec);
  if (ec || results.empty())
    throw VideoError("video: cannot resolve destination '" + s_.host + "': " + ec.message());
  net_->dest = *results.begin();
  net_->socket.open(asio::ip::udp::v4(), ec);
  if (ec) throw VideoError("video: cannot open a UDP socket: " + ec.message());
  // Room for a whole 1080p IDR's packets, so a burst is not dropped locally.
  net_->socket.set_option(asio::socket_base::send_buffer_size(1 << 20), ec);
  st_.ssrc = ssrc_;
  st_.rtx_ssrc = rtx_ssrc_;
  rate_ = RateController(rateSettings(s_), monoNowUs());
}

VideoSender::~VideoSender() { stop(); }

void VideoSender::start() {
  if (running_.exchange(true)) return;
  keyframe_requested_ = true;
  // Named, so that top -H and bench_loop's CPU per thread say which is which
  // (the encoder's own threads inherit "<prefix>-encode"). The settings are
  // read here, before the threads run: apply() may change s_ under mu_ later.
  bool stream = true, retransmission = true;
  std::string prefix;
  {
    std::lock_guard lk(mu_);
    stream = s_.stream;
    retransmission = s_.retransmission;
    prefix = s_.thread_prefix;
  }
  const auto named = [](const std::string& name) { pthread_setname_np(pthread_self(), name.substr(0, 15).c_str()); };
  capture_thread_ = std::thread([this, named, n = prefix + "-capture"] {
    named(n);
    captureLoop();
  });
  if (!stream) return;
  encode_thread_ = std::thread([this, named, n = prefix + "-encode"] {
    named(n);
    encodeLoop();
  });
  if (retransmission)
    feedback_thread_ = std::thread([this, named, n = prefix + "-rtcp"] {
      named(n);
      feedbackLoop();
    });
}

void VideoSender::stop() {
  {
    std::lock_guard lk(mu_);
    if (!running_.exchange(false)) return;
  }
  wake_cv_.notify_all();
  frame_cv_.notify_all();
  if (capture_thread_.joinable()) capture_thread_.join();
  if (encode_thread_.joinable()) encode_thread_.join();
  if (feedback_thread_.joinable()) feedback_thread_.join();
}

std::string VideoSender::apply(const SenderChange& c) {
  std::lock_guard lk(mu_);
  SenderSettings n = s_;
  if (c.enabled) n.enabled = *c.enabled;
  if (c.width.has_value() != c.height.has_value()) return "video: width and height go together";
  if (c.width) {
    n.source.width = *c.width;
    n.source.height = *c.height;
  }
  if (c.fps) n.source.fps = *c.fps;
  if (c.bitrate_kbps) n.encoder.bitrate_kbps = *c.bitrate_kbps;
  if (auto why = validate(n); !why.empty()) return why;
  const bool restart = n.source.width != s_.source.width || n.source.height != s_.source.height ||
                       n.source.fps != s_.source.fps;
  if (restart) ++generation_;
  // The operator's bitrate is the new ceiling and the rate in force (in place,
  // no keyframe); the controller holds the range from here on.
  if (c.bitrate_kbps) rate_.setOperatorRate(monoNowUs(), *c.bitrate_kbps);
  if (n.enabled && !s_.enabled) keyframe_requested_ = true;
  s_ = n;
  wake_cv_.notify_all();
  return {};
}

void VideoSender::requestKeyframe() {
  keyframe_requested_ = true;
  std::lock_guard lk(mu_);
  ++st_.keyframe_requests;
}

SenderStats VideoSender::stats() const {
  std::lock_guard lk(mu_);
  SenderStats s = st_;
  s.enabled = s_.enabled;
  s.width = s_.source.width;
  s.height = s_.source.height;
  s.fps = s_.source.fps;
  s.bitrate_kbps = s_.encoder.bitrate_kbps;
  s.source = s_.source.uri;
  s.port = s_.port;
  const RateState& r = rate_.state();
  const EncoderSettings e = adaptedEncoder(s_, r);
  s.adapt = rate_.settings().enabled;
  s.min_kbps = rate_.settings().min_kbps;
  s.max_kbps = rate_.settings().max_kbps;
  s.rate_kbps = r.kbps;
  s.send_width = e.width;
  s.send_height = e.height;
  s.send_fps = e.fps;
  s.rate_level = r.level;
  s.rate_reason = r.reason;
  s.rate_changed_us = r.changed_us;
  s.rate_changes = r.changes;
  return s;
}

void VideoSender::setError(const std::string& e) {
  {
    std::lock_guard lk(mu_);
    if (st_.error == e) return;
    st_.error = e;
  }
  log::warn(log::tag::kVideo, e);
}

void VideoSender::captureLoop() {
  std::unique_ptr<FrameSource> src;
  uint64_t src_generation = ~0ull;
  uint32_t index = 0;
  Clock::time_point next = Clock::now();
  std::unique_lock lk(mu_);
  while (running_) {
    if (!s_.enabled) {
      src.reset();  // release the camera while off
      wake_cv_.wait_for(lk, std::chrono::milliseconds(200));
      continue;
    }
    const SourceSettings ss = s_.source;
    const uint64_t gen = generation_;
    lk.unlock();
    if (!src || gen != src_generation) {
      try {
        src = openFrameSource(ss);
        src_generation = gen;
        next = Clock::now();
        log::info(log::tag::kVideo, "source ", src->describe(), " ", ss.width, "x", ss.height, " @ ", ss.fps, " fps");
      } catch (const VideoError& e) {
        src.reset();
        setError(e.what());
        lk.lock();
        wake_cv_.wait_for(lk, std::chrono::seconds(1), [this] { return !running_; });  // retry later
        continue;
      }
    }
    const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / ss.fps));
    if (!src->paced()) {
      lk.lock();
      if (wake_cv_.wait_until(lk, next, [this] { return !running_; })) break;
      lk.unlock();
      next += period;
      if (Clock::now() - next > period) next = Clock::now();  // fell behind: no burst to catch up
    }
    cv::Mat frame;
    uint64_t capture_us = monoNowUs();
    if (!src->read(frame, capture_us, index)) {
      setError("video: " + src->describe() + ": " + (src->error().empty() ? "no frame" : src->error()));
      src.reset();
      lk.lock();
      wake_cv_.wait_for(lk, std::chrono::seconds(1), [this] { return !running_; });
      continue;
    }
    if (src->paced()) capture_us = monoNowUs();  // a camera's frame is ready when read() returns
    if (tap_) tap_(frame, capture_us);
    lk.lock();
    if (!s_.stream) {
      ++index;
      ++st_.captured;
      continue;
    }
    if (slot_full_) ++st_.dropped;
    slot_ = std::move(frame);
    slot_capture_us_ = capture_us;
    slot_index_ = index++;
    slot_generation_ = gen;
    slot_full_ = true;
    ++st_.captured;
    frame_cv_.notify_one();
  }
}

void VideoSender::prepareEncoder(std::unique_ptr<H264Encoder>& enc, uint64_t& enc_generation, uint64_t gen,
                                 const EncoderSettings& es) {
  if (enc && gen == enc_generation &&
      (es.width != enc->settings().width || es.height != enc->settings().height || es.fps != enc->settings().fps))
    enc_generation = ~0ull;  // a new level: reopened with an IDR
  if (enc && gen == enc_generation && es.bitrate_kbps != enc->settings().bitrate_kbps) {
    try {
      if (!enc->setBitrate(es.bitrate_kbps)) enc_generation = ~0ull;  // no in-place change: reopen
    } catch (const VideoError& e) {
      setError(e.what());
    }
  }
  if (enc && gen == enc_generation) return;
  try {
    enc.reset();
    enc = std::make_unique<H264Encoder>(es);
    enc_generation = gen;
    keyframe_requested_ = true;
    std::string why;
    {
      std::lock_guard rl(mu_);
      if (rate_.state().changes > 0) why = " (rate adaptation: " + rate_.state().reason + ")";
    }
    log::info(log::tag::kVideo, "encoder ", enc->codecName(), " ", es.width, "x", es.height, " @ ", es.fps, " fps, ",
              es.bitrate_kbps, " kbit/s, GOP ", es.gop, es.intra_refresh ? ", intra refresh" : "", why);
  } catch (const VideoError& e) {
    enc.reset();
    setError(e.what());
  }
}

void VideoSender::sendFrame(H264Packetizer& packetizer, const EncodedFrame& out, uint64_t capture_us,
                            std::vector<std::vector<uint8_t>>& packets, SentFigures& f) {
  packets.clear();
  const auto ts = static_cast<uint32_t>(capture_us * 9 / 100);  // 90 kHz from microseconds
  packetizer.packetize(out.annexb, ts, capture_us, packets);
  const uint64_t now_us = monoNowUs();
  for (const auto& p : packets) {
    if (!net_->send(p, &f.error)) {
      ++f.send_errors;
      continue;
    }
    ++f.packets;
    f.bytes += p.size();
    std::lock_guard hl(net_->history_mu);
    net_->history.remember(static_cast<uint16_t>(p[2] << 8 | p[3]), p, now_us);
    net_->last_rtp_ts = ts;
    ++net_->packets_sent;
    net_->octets_sent += static_cast<uint32_t>(p.size() - kRtpHeaderSize);
  }
}

void VideoSender::encodeLoop() {
  std::unique_ptr<H264Encoder> enc;
  uint64_t enc_generation = ~0ull;
  std::unique_ptr<H264Packetizer> packetizer;
  std::vector<std::vector<uint8_t>> packets;
  EncodedFrame out;
  uint64_t skip_phase = 0;
  double window_ms = 0;
  int window_n = 0;
  Clock::time_point window_start = Clock::now();

  std::unique_lock lk(mu_);
  while (running_) {
    frame_cv_.wait_for(lk, std::chrono::milliseconds(200), [this] { return slot_full_ || !running_; });
    if (!running_) break;
    if (!slot_full_) continue;
    cv::Mat frame = std::move(slot_);
    slot_full_ = false;
    const uint64_t capture_us = slot_capture_us_;
    const uint32_t index = slot_index_;
    const uint64_t gen = slot_generation_;
    rate_.tick(monoNowUs());
    const int level = rate_.state().level;  // the reason is read only when the encoder reopens
    const EncoderSettings es = adaptedEncoder(s_, rate_.state());
    const int source_width = s_.source.width, source_height = s_.source.height;
    const std::size_t mtu = s_.mtu;
    const bool current = gen == generation_;
    // At a reduced frame rate, every fps-divisor-th picture only.
    const int divisor = RateController::fpsDivisor(level);
    if (current && divisor > 1 && skip_phase++ % divisor != 0) {
      ++st_.rate_skipped;
      continue;
    }
    if (divisor == 1) skip_phase = 0;
    lk.unlock();

    if (current) prepareEncoder(enc, enc_generation, gen, es);
    if (!packetizer) packetizer = std::make_unique<H264Packetizer>(ssrc_, mtu - kOverhead, static_cast<uint16_t>(ssrc_));
    bool sent = false;
    SentFigures sent_figures;
    double ms = 0;
    if (current && frame.cols == source_width && frame.rows == source_height &&
        (frame.cols != es.width || frame.rows != es.height))
      cv::resize(frame, frame, cv::Size(es.width, es.height), 0, 0, cv::INTER_AREA);
    if (current && enc && frame.cols == es.width && frame.rows == es.height) {
      const bool force = keyframe_requested_.exchange(false);
      const auto t0 = Clock::now();
      try {
        sent = enc->encode(frame, capture_us, index, force, out);
      } catch (const VideoError& e) {
        setError(e.what());
        enc.reset();  // reopened with the next frame
      }
      ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      if (sent) sendFrame(*packetizer, out, capture_us, packets, sent_figures);
    }
    if (!sent_figures.error.empty()) setError(sent_figures.error);
    lk.lock();
    if (!current) ++st_.dropped;  // captured with the settings before a change
    if (sent) {
      ++st_.encoded;
      if (out.keyframe) ++st_.keyframes;
      st_.packets += sent_figures.packets;
      st_.bytes += sent_figures.bytes;
      st_.send_errors += sent_figures.send_errors;
      if (enc) st_.encoder = enc->codecName();
      window_ms += ms;
      ++window_n;
    }
    if (Clock::now() - window_start >= std::chrono::seconds(1)) {
      st_.encode_ms = window_n ? window_ms / window_n : 0;
      window_ms = 0;
      window_n = 0;
      window_start = Clock::now();
    }
  }
}

void VideoSender::feedbackLoop() {
  std::vector<uint8_t> buf(2048);
  auto next_sr = Clock::now();
  while (running_) {
    if (Clock::now() >= next_sr) {
      sendSenderReport();
      next_sr = Clock::now() + std::chrono::seconds(1);
    }
    // Wait for RTCP at most 50 ms at a time, so that stop() returns soon
    // (asio's blocking read would wait for ever: it polls again on EAGAIN).
    pollfd pfd{net_->socket.native_handle(), POLLIN, 0};
    if (::poll(&pfd, 1, 50) <= 0) continue;
    asio::ip::udp::endpoint from;
    boost::system::error_code ec;
    const std::size_t n = net_->socket.receive_from(asio::buffer(buf), from, 0, ec);
    if (ec) continue;  // an ICMP error of an earlier send (nobody listening yet)
    if (from != net_->dest) continue;  // only the destination gives feedback
    onFeedback(std::span<const uint8_t>(buf.data(), n));
  }
}

void VideoSender::sendSenderReport() {
  rtcp::SenderInfo info;
  {
    std::lock_guard hl(net_->history_mu);
    if (net_->packets_sent == 0) return;  // nothing to map yet
    info.packets = net_->packets_sent;
    info.octets = net_->octets_sent;
  }
  // The RTP clock is the capture clock (CLOCK_MONOTONIC) at 90 kHz; the NTP
  // time is the wall clock at the same instant.
  info.rtp_timestamp = static_cast<uint32_t>(monoNowUs() * 9 / 100);
  info.ntp = rtcp::ntpFromUnixMicros(wallNowNs() / 1000);
  std::vector<uint8_t> d;
  rtcp::appendSenderReport(d, ssrc_, info);
  rtcp::appendCname(d, ssrc_, "inspect-robot-" + std::to_string(ssrc_));
  if (net_->send(d, nullptr)) {
    std::lock_guard lk(mu_);
    ++st_.sender_reports;
  }
}

void VideoSender::onFeedback(std::span<const uint8_t> datagram) {
  rtcp::Compound c;
  const rtcp::RtcpError e = rtcp::parseCompound(datagram, c);
  if (e != rtcp::RtcpError::kNone) {
    std::lock_guard lk(mu_);
    ++st_.rtcp_errors;
    st_.error = std::string("video: RTCP from the receiver: ") + rtcp::toString(e);
    return;
  }
  const uint64_t now_mono_us = monoNowUs();
  const uint32_t now_middle = rtcp::ntpMiddle(rtcp::ntpFromUnixMicros(wallNowNs() / 1000));
  std::optional<double> rtt_s, loss;
  uint64_t blocks = 0;
  for (const auto& rr : c.receiver_reports)
    for (const auto& b : rr.blocks) {
      if (b.ssrc != ssrc_) continue;
      ++blocks;
      loss = b.fraction_lost / 2.56;
      if (auto r = rtcp::roundTripSeconds(now_middle, b.lsr, b.dlsr)) rtt_s = r;
    }
  uint64_t asked = 0, sent = 0, missed = 0, nacks = 0, repeats = 0;
  const uint64_t now_us = monoNowUs();
  for (const auto& n : c.nacks) {
    if (n.media_ssrc != ssrc_) continue;
    ++nacks;
    for (uint16_t seq : n.seqs) {
      ++asked;
      std::vector<std::vector<uint8_t>> rtx;
      bool held = false;
      {
        std::lock_guard hl(net_->history_mu);
        const auto plan = net_->history.planRetransmission(seq, now_us, kRepeatNackUs);
        held = plan.datagram != nullptr;
        for (int k = 0; k < plan.copies; ++k)
          if (auto r = makeRtx(*plan.datagram, rtx_ssrc_, kRtxPayloadType, net_->rtx_seq++)) rtx.push_back(std::move(*r));
      }
      if (!held) ++missed;
      else if (rtx.empty()) ++repeats;
      for (const auto& r : rtx)
        if (net_->send(r, nullptr)) ++sent;
    }
  }
  uint64_t plis = 0;
  for (const auto& p : c.plis)
    if (p.media_ssrc == ssrc_) ++plis;
  if (plis) keyframe_requested_ = true;
  std::lock_guard lk(mu_);
  if (loss) rate_.onReport(now_mono_us, *loss / 100.0, rtt_s ? std::optional<double>(*rtt_s * 1000.0) : std::nullopt);
  st_.receiver_reports += blocks;
  if (loss) st_.peer_loss_pct = *loss;
  if (rtt_s) st_.rtt_ms = *rtt_s * 1000.0;
  st_.nacks += nacks;
  st_.nacked_packets += asked;
  st_.retransmitted += sent;
  st_.not_in_history += missed;
  st_.repeat_nacks += repeats;
  st_.plis += plis;
  st_.keyframe_requests += plis;
}

}  // namespace inspect::video
