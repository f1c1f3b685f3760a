#include "shared/video/video_receiver.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include <boost/asio/post.hpp>

#include "shared/util/clock.hpp"
#include "shared/util/log.hpp"
#include "shared/video/rtcp.hpp"
#include "shared/video/rtx.hpp"

namespace inspect::video {

namespace asio = boost::asio;
using Clock = std::chrono::steady_clock;

namespace {
constexpr std::size_t kMaxDatagram = 65536;
constexpr auto kTick = std::chrono::milliseconds(100);
constexpr int kTicksPerWindow = 10;            // rates over 1 s
constexpr std::size_t kLatencyHistory = 300;
constexpr uint32_t kReceiverSsrc = 0x5E55AE01;  // the server's RTCP SSRC (it sends no media)
constexpr std::size_t kNackWindow = 1024;        // packets a gap may hold behind it while waiting for RTX
constexpr auto kRepairTick = std::chrono::milliseconds(3);  // NACK retries and give-ups while a gap waits
// A frame's packets leave the robot back to back: a frame without its marker
// packet this long after its newest packet has probably lost its tail (NackList::probeTail).
constexpr uint64_t kTailWaitUs = 4000;

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return -1;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5);
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}
}  // namespace

struct VideoReceiver::Stream {
  Stream(uint32_t ssrc_, asio::ip::address source_, int64_t offset, std::size_t window, bool decode)
      : ssrc(ssrc_), source(std::move(source_)), offset_us(offset), reorder(window), nacks(nackSettings()) {
    if (decode) decoder = std::make_unique<H264Decoder>();
  }
  uint32_t ssrc;
  asio::ip::address source;
  int64_t offset_us;
  ReorderBuffer reorder;
  H264Depacketizer depack;
  std::unique_ptr<H264Decoder> decoder;
  // The picture is damaged (a frame was dropped or skipped, or the decoder
  // failed) until a keyframe decodes: request keyframes, freeze the picture.
  bool damaged = false;
  Clock::time_point last_request{};
  Clock::time_point gap_since{};  // packets held behind a missing one since; {} = none held
  Clock::time_point last_packet{};
  StreamStats st;
  std::vector<uint8_t> sps, pps;
  std::deque<double> latencies;  // ms, last kLatencyHistory decoded frames
  // Current 1 s window.
  uint64_t w_bytes = 0, w_frames = 0, w_decoded = 0, w_packets = 0, w_lost = 0;
  double w_latency_sum = 0;
  uint64_t w_latency_n = 0;
  std::vector<std::pair<uint32_t, std::vector<uint8_t>>> ready;  // scratch
  // RTCP feedback.
  rtcp::ReceiverStats rstats;
  NackList nacks;
  asio::ip::udp::endpoint feedback_to;  // where this stream's RTP comes from; unset = nothing yet
  struct NackTimes {
    uint64_t first_us = 0, last_us = 0;
    int count = 0;
  };
  std::map<uint16_t, NackTimes> nacked_at_us;  // per sequence number NACKed, for the RTT
  // Assumed high until measured: only a first try's answer is an exact
  // sample (Karn), and an over-estimate corrects itself with the first one,
  // while an under-estimate retries before any answer can come.
  double rtt_us = 100000;
  bool rtt_measured = false;

  // The RTT from an RTX packet of `seq` (needed or not). One NACK: an exact
  // sample (1/8 gain). More: which one it answers is unknown, but now - the
  // last is a lower bound; taken when it exceeds the estimate (a link whose
  // RTT rose must not stay stuck with retries that come too soon to sample).
  void sampleRtt(uint16_t seq, uint64_t now_us) {
    const auto it = nacked_at_us.find(seq);
    if (it == nacked_at_us.end() || now_us < it->second.last_us) return;
    if (it->second.count == 1) {
      const double sample = static_cast<double>(now_us - it->second.first_us);
      rtt_us = rtt_measured ? 0.875 * rtt_us + 0.125 * sample : sample;  // RFC 6298-style smoothing
    } else if (const double lower = static_cast<double>(now_us - it->second.last_us); lower > rtt_us) {
      rtt_us = lower;
    } else {
      return;
    }
    rtt_measured = true;
    st.rtt_ms = rtt_us / 1000.0;
  }
  // The newest packet had no marker (its frame is still open) since newest_us; probed once.
  bool tail_open = false, tail_probed = false;
  uint64_t newest_us = 0;

  static NackSettings nackSettings() {
    NackSettings n;
    n.reorder_wait_us = 0;  // loss on Wi-Fi is far more common than reordering: ask at once
    return n;
  }
};

VideoReceiver::VideoReceiver(ReceiverSettings s)
    : settings_(std::move(s)), socket_(io_), tick_timer_(io_), repair_timer_(io_), rx_buf_(kMaxDatagram) {
  settings_.nack = settings_.nack && settings_.rtcp;  // NACKs are RTCP
  boost::system::error_code ec;
  const auto addr = asio::ip::make_address(settings_.bind, ec);
  if (ec) throw VideoError("video receiver: bad bind address '" + settings_.bind + "'");
  const asio::ip::udp::endpoint ep(addr, settings_.port);
  socket_.open(ep.protocol(), ec);
  if (!ec) socket_.set_option(asio::socket_base::receive_buffer_size(4 << 20), ec);
  ec.clear();
  if (!ec) socket_.bind(ep, ec);
  if (ec)
    throw VideoError("video receiver: cannot bind UDP " + settings_.bind + ":" + std::to_string(settings_.port) +
                     ": " + ec.message());
  port_ = socket_.local_endpoint().port();
}

VideoReceiver::~VideoReceiver() { stop(); }

void VideoReceiver::start() {
  if (started_) return;
  started_ = true;
  doReceive();
  tick_timer_.expires_after(kTick);
  tick_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec) tick();
  });
  thread_ = std::thread([this] { io_.run(); });
}

void VideoReceiver::stop() {
  if (!started_) return;
  started_ = false;
  io_.stop();
  if (thread_.joinable()) thread_.join();
}

void VideoReceiver::setStream(const std::string& name, uint32_t ssrc, const asio::ip::address& source,
                              int64_t clock_offset_us) {
  {
    std::lock_guard lk(mu_);
    published_[name].stats.ssrc = ssrc;
  }
  asio::post(io_, [this, name, ssrc, source, clock_offset_us] {
    auto& s = streams_[name];
    if (s && s->ssrc == ssrc && s->source == source) {
      s->offset_us = clock_offset_us;
      return;
    }
    s = std::make_unique<Stream>(ssrc, source, clock_offset_us,
                                 settings_.nack ? std::max(settings_.reorder_window, kNackWindow) : settings_.reorder_window,
                                 settings_.decode);
    s->st.ssrc = ssrc;
    log::info(log::tag::kVideo, name, ": expecting SSRC ", ssrc, " from ", source.is_unspecified() ? "any address" : source.to_string());
  });
}

void VideoReceiver::setClockOffset(const std::string& name, int64_t clock_offset_us) {
  asio::post(io_, [this, name, clock_offset_us] {
    if (auto it = streams_.find(name); it != streams_.end()) it->second->offset_us = clock_offset_us;
  });
}

void VideoReceiver::removeStream(const std::string& name) {
  asio::post(io_, [this, name] {
    streams_.erase(name);
    std::lock_guard lk(mu_);
    published_[name].stats.active = false;
  });
}

void VideoReceiver::checkNotStarted() const {
  // The receiver thread reads the hooks without a lock.
  if (started_) throw std::logic_error("VideoReceiver: hooks are set before start()");
}
void VideoReceiver::setKeyframeRequest(KeyframeRequest f) {
  checkNotStarted();
  keyframe_request_ = std::move(f);
}
void VideoReceiver::setFrameHook(FrameHook f) {
  checkNotStarted();
  frame_hook_ = std::move(f);
}
void VideoReceiver::setAccessUnitHook(AccessUnitHook f) {
  checkNotStarted();
  access_unit_hook_ = std::move(f);
}
void VideoReceiver::setPacketHook(PacketHook f) {
  checkNotStarted();
  packet_hook_ = std::move(f);
}

std::optional<StreamStats> VideoReceiver::stats(const std::string& name) const {
  std::lock_guard lk(mu_);
  auto it = published_.find(name);
  if (it == published_.end()) return std::nullopt;
  return it->second.stats;
}

ReceiverCounters VideoReceiver::counters() const {
  std::lock_guard lk(mu_);
  return counters_;
}

bool VideoReceiver::latestFrame(const std::string& name, cv::Mat& bgr, uint64_t* capture_us) const {
  std::lock_guard lk(mu_);
  auto it = published_.find(name);
  if (it == published_.end() || it->second.latest.empty()) return false;
  bgr = it->second.latest;
  if (capture_us) *capture_us = it->second.latest_capture_us;
  return true;
}

bool VideoReceiver::parameterSets(const std::string& name, std::vector<uint8_t>& sps, std::vector<uint8_t>& pps) const {
  std::lock_guard lk(mu_);
  auto it = published_.find(name);
  if (it == published_.end() || it->second.sps.empty() || it->second.pps.empty()) return false;
  sps = it->second.sps;
  pps = it->second.pps;
  return true;
}

void VideoReceiver::doReceive() {
  socket_.async_receive_from(asio::buffer(rx_buf_), sender_, [this](const boost::system::error_code& ec, std::size_t n) {
    if (ec == asio::error::operation_aborted) return;
    if (!ec) onDatagram(n);
    doReceive();
  });
}

void VideoReceiver::onDatagram(std::size_t n) {
  const std::span<const uint8_t> data(rx_buf_.data(), n);
  if (rtcp::looksLikeRtcp(data)) {  // RFC 5761 4: payload types 192-223 on the RTP port are RTCP
    {
      std::lock_guard lk(mu_);
      ++counters_.datagrams;
      ++counters_.rtcp;
    }
    return onRtcp(data);
  }
  RtpPacket p;
  const RtpError err = parseRtp(data, p);
  const auto reject = [&](uint64_t ReceiverCounters::*counter, const std::string& why) {
    std::lock_guard lk(mu_);
    ++counters_.datagrams;
    ++(counters_.*counter);
    counters_.last_reject = "from " + sender_.address().to_string() + ":" + std::to_string(sender_.port()) + ": " + why;
  };
  if (err != RtpError::kNone) return reject(&ReceiverCounters::not_rtp, std::string("not RTP: ") + toString(err));
  if (p.payload_type == kRtxPayloadType && settings_.nack) return onRtx(data);
  if (p.payload_type != kPayloadType)
    return reject(&ReceiverCounters::wrong_payload_type, "payload type " + std::to_string(p.payload_type));
  for (auto& [name, s] : streams_) {
    if (s->ssrc != p.ssrc) continue;
    if (!s->source.is_unspecified() && s->source != sender_.address())
      return reject(&ReceiverCounters::wrong_source, "SSRC " + std::to_string(p.ssrc) + " of " + name +
                                                         " from another address than the robot's");
    {
      std::lock_guard lk(mu_);
      ++counters_.datagrams;
    }
    s->feedback_to = sender_;
    s->rstats.onPacket(p.seq, p.timestamp, monoNowUs());
    handlePacket(*s, name, p.seq, std::vector<uint8_t>(data.begin(), data.end()));
    return;
  }
  reject(&ReceiverCounters::unknown_ssrc, "unknown SSRC " + std::to_string(p.ssrc));
}

void VideoReceiver::onRtcp(std::span<const uint8_t> data) {
  rtcp::Compound c;
  if (rtcp::parseCompound(data, c) != rtcp::RtcpError::kNone) return;  // counted as rtcp; nothing to use
  for (const auto& sr : c.sender_reports)
    for (auto& [name, s] : streams_)
      if (s->ssrc == sr.ssrc && s->feedback_to == sender_) s->rstats.onSenderReport(sr.info.ntp, monoNowUs());
}

void VideoReceiver::onRtx(std::span<const uint8_t> data) {
  // An RTX packet belongs to the stream whose media comes from the same
  // address and port (the robot sends both from one socket).
  for (auto& [name, s] : streams_) {
    if (s->feedback_to != sender_) continue;
    std::vector<uint8_t> orig;
    if (unwrapRtx(data, kRtxPayloadType, kPayloadType, s->ssrc, orig) != RtxError::kNone) return;
    const uint16_t seq = static_cast<uint16_t>(orig[2] << 8 | orig[3]);
    {
      std::lock_guard lk(mu_);
      ++counters_.datagrams;
    }
    s->sampleRtt(seq, monoNowUs());  // a late answer to a given-up packet still tells the RTT
    if (!s->nacks.missing(seq)) {
      ++s->st.rtx_unneeded;
      return;
    }
    ++s->st.retransmissions;  // not counted in rstats: the reports give the loss on the wire
    handlePacket(*s, name, seq, std::move(orig), true);
    return;
  }
  std::lock_guard lk(mu_);
  ++counters_.datagrams;
  ++counters_.unknown_ssrc;
  counters_.last_reject = "from " + sender_.address().to_string() + ":" + std::to_string(sender_.port()) +
                          ": RTX from an address no stream's media comes from";
}

void VideoReceiver::sendFeedback(Stream& s, const std::vector<uint8_t>& d) {
  if (s.feedback_to.port() == 0 || d.empty()) return;
  boost::system::error_code ec;
  socket_.send_to(asio::buffer(d), s.feedback_to, 0, ec);  // loss of feedback is recovered by the next one
}

void VideoReceiver::sendNacks(Stream& s) {
  if (!settings_.nack) return;
  const uint64_t now_us = monoNowUs();
  const auto due = s.nacks.due(now_us, static_cast<uint64_t>(s.rtt_us));
  if (due.empty()) return;
  std::vector<uint8_t> d;
  rtcp::appendNack(d, kReceiverSsrc, s.ssrc, due);
  // Twice: a lost NACK costs a whole retry interval, and both copies are lost
  // only with the loss rate squared. The robot answers the second copy only
  // when the first was lost (VideoSender ignores a repeat within a few ms).
  sendFeedback(s, d);
  sendFeedback(s, d);
  ++s.st.nacks_sent;
  s.st.nacked_packets += due.size();
  for (uint16_t q : due)
    if (auto [it, fresh] = s.nacked_at_us.try_emplace(q, Stream::NackTimes{now_us, now_us, 1}); !fresh) {
      if (now_us > it->second.last_us + 1'000'000) {
        it->second = {now_us, now_us, 1};  // a sequence number reused since (the 16-bit wrap)
      } else {
        it->second.last_us = now_us;
        ++it->second.count;
      }
    }
  while (s.nacked_at_us.size() > kNackWindow) s.nacked_at_us.erase(s.nacked_at_us.begin());
}

Clock::duration VideoReceiver::gapWait(const Stream& s) const {
  const double base = settings_.reorder_timeout_s;
  if (!settings_.nack) return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(base));
  // Time for every try: the first NACK's round trip, then a retry interval
  // per further try (NackList), plus scheduling slack; at most max_wait_s.
  const NackSettings& n = s.nacks.settings();
  const double rtt_s = s.rtt_us / 1e6;
  const double retry_s = std::max(n.min_retry_us / 1e6, n.retry_rtts * rtt_s);
  const double w = std::clamp(n.reorder_wait_us / 1e6 + rtt_s + retry_s * (n.max_tries - 1) + 0.010, base,
                              std::max(base, settings_.max_wait_s));
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(w));
}

void VideoReceiver::handlePacket(Stream& s, const std::string& name, uint16_t seq, std::vector<uint8_t> datagram,
                                 bool retransmitted) {
  const auto now = Clock::now();
  if (settings_.nack) {
    const uint64_t now_us = monoNowUs();
    s.nacks.onPacket(seq, now_us);
    if (s.nacks.highest() == seq && datagram.size() > 1) {
      s.tail_open = !(datagram[1] & 0x80);  // the marker bit
      s.tail_probed = false;
      s.newest_us = now_us;
    }
  }
  if (retransmitted) s.nacked_at_us.erase(seq);
  s.last_packet = now;
  ++s.st.packets;
  ++s.w_packets;
  s.st.bytes += datagram.size();
  s.w_bytes += datagram.size();
  if (packet_hook_) packet_hook_(name, datagram);
  s.reorder.push(seq, std::move(datagram));
  s.ready.clear();
  s.reorder.pop(s.ready);
  // A gap is given up after its wait even when fewer than `window` packets
  // wait behind it: a loss must freeze the picture and ask for a keyframe
  // at once, not 16 packets later.
  if (s.reorder.held() == 0) s.gap_since = {};
  else if (s.gap_since == Clock::time_point{} || !s.ready.empty()) s.gap_since = headGapSince(s, now);
  giveUpStaleGaps(s, now);
  sendNacks(s);
  depacketizeReady(s, name);
  armRepair();
  maybeRequestKeyframe(s, name);
}

void VideoReceiver::depacketizeReady(Stream& s, const std::string& name) {
  for (auto& [skipped, dgram] : s.ready) {
    RtpPacket p;
    if (parseRtp(dgram, p) != RtpError::kNone) continue;
    const uint64_t dropped_before = s.depack.counters().frames_dropped;
    auto f = s.depack.push(p, skipped);
    if (s.depack.counters().frames_dropped != dropped_before) s.damaged = true;
    if (f) onFrame(s, name, *f);
  }
  s.ready.clear();
}

void VideoReceiver::maybeRequestKeyframe(Stream& s, const std::string& name) {
  const auto now = Clock::now();
  if (!s.damaged || now - s.last_request < std::chrono::duration<double>(settings_.keyframe_min_interval_s)) return;
  s.last_request = now;
  ++s.st.keyframe_requests;
  if (keyframe_request_) keyframe_request_(name);
  if (settings_.rtcp) {  // and over RTCP, which reaches the robot without the TCP link's queue
    std::vector<uint8_t> d;
    rtcp::appendPli(d, kReceiverSsrc, s.ssrc);
    sendFeedback(s, d);
    ++s.st.plis_sent;
  }
}

void VideoReceiver::onFrame(Stream& s, const std::string& name, const Frame& f) {
  ++s.w_frames;
  if (f.has_parameter_sets) {
    for (auto nal : splitAnnexB(f.annexb)) {
      if (nalType(nal[0]) == kNalSps) s.sps.assign(nal.begin(), nal.end());
      if (nalType(nal[0]) == kNalPps) s.pps.assign(nal.begin(), nal.end());
    }
  }
  uint64_t capture_server_us = 0;
  // Unsigned: a capture time from the wire may be anything; it wraps instead of overflowing.
  if (f.capture_us) capture_server_us = *f.capture_us + static_cast<uint64_t>(s.offset_us);
  if (access_unit_hook_) access_unit_hook_(name, f, capture_server_us);
  if (!s.decoder) return;
  // After a loss the picture stays frozen until a keyframe: P frames that
  // reference a lost frame would only smear the damage (as WebRTC does).
  // The same before the first keyframe (a stream joined mid-GOP).
  if (!f.keyframe && (s.damaged || s.depack.needKeyframe())) {
    ++s.st.frames_skipped;
    s.damaged = true;
    return;
  }
  cv::Mat bgr;  // fresh per picture: published by reference count
  if (!s.decoder->decode(f.annexb.data(), f.annexb.size(), bgr)) {
    if (s.decoder->counters().errors > s.st.decode_errors) {
      s.st.decode_errors = s.decoder->counters().errors;
      s.damaged = true;
      log::debug(log::tag::kVideo, name, ": decode error: ", s.decoder->lastError());
    }
    return;
  }
  if (f.keyframe) s.damaged = false;
  ++s.st.decoded;
  ++s.w_decoded;
  s.st.width = bgr.cols;
  s.st.height = bgr.rows;
  if (f.capture_us) {
    const double ms = (static_cast<double>(monoNowUs()) - static_cast<double>(capture_server_us)) / 1000.0;
    s.w_latency_sum += ms;
    ++s.w_latency_n;
    s.latencies.push_back(ms);
    if (s.latencies.size() > kLatencyHistory) s.latencies.pop_front();
  }
  {
    std::lock_guard lk(mu_);
    auto& pub = published_[name];
    pub.latest = bgr;
    pub.latest_capture_us = capture_server_us;
  }
  if (frame_hook_) frame_hook_(name, bgr, capture_server_us);
}

Clock::time_point VideoReceiver::headGapSince(const Stream& s, Clock::time_point now) const {
  // With repair, each gap waits from when it was found (the NACK list knows);
  // else from when it became the first (a gap only waits for reordering).
  if (settings_.nack)
    if (const auto first = s.nacks.firstMissedUs(s.reorder.next())) {
      const uint64_t now_us = monoNowUs();
      return now - std::chrono::microseconds(now_us > *first ? now_us - *first : 0);
    }
  return now;
}

void VideoReceiver::giveUpStaleGaps(Stream& s, Clock::time_point now) {
  // With repair, gap by gap (the ones behind are younger and still being
  // repaired); without, everything held at once (nothing will fill them).
  while (s.reorder.held() > 0 && s.gap_since != Clock::time_point{} && now - s.gap_since >= gapWait(s)) {
    if (settings_.nack) s.reorder.skipGap(s.ready);
    else s.reorder.flush(s.ready);
    s.gap_since = s.reorder.held() > 0 ? headGapSince(s, now) : Clock::time_point{};
  }
  // What is no longer held behind a gap is given up (nothing more to NACK).
  if (s.nacks.size() > 0) (void)s.nacks.expireBefore(s.reorder.next());
}

void VideoReceiver::releaseStaleGap(Stream& s, const std::string& name, Clock::time_point now) {
  // A gap nobody will fill (lost for good, or the stream paused): release what waits behind it.
  s.ready.clear();
  giveUpStaleGaps(s, now);
  if (s.ready.empty()) return;
  depacketizeReady(s, name);
  maybeRequestKeyframe(s, name);
}

void VideoReceiver::armRepair() {
  if (repair_armed_) return;
  const bool nack = settings_.nack;
  const bool waiting = std::any_of(streams_.begin(), streams_.end(), [nack](const auto& e) {
    const Stream& s = *e.second;
    return s.reorder.held() > 0 || s.nacks.size() > 0 || (nack && s.tail_open && !s.tail_probed);
  });
  if (!waiting) return;
  repair_armed_ = true;
  repair_timer_.expires_after(kRepairTick);
  repair_timer_.async_wait([this](const boost::system::error_code& ec) {
    repair_armed_ = false;
    if (!ec) repairTick();
  });
}

void VideoReceiver::repairTick() {
  const auto now = Clock::now();
  const uint64_t now_us = monoNowUs();
  for (auto& [name, sp] : streams_) {
    Stream& s = *sp;
    releaseStaleGap(s, name, now);
    if (!settings_.nack) continue;
    if (s.tail_open && !s.tail_probed && now_us >= s.newest_us + kTailWaitUs) {
      s.tail_probed = true;
      if (s.nacks.probeTail(now_us)) ++s.st.tail_probes;
    }
    sendNacks(s);
  }
  armRepair();
}

void VideoReceiver::tick() {
  const auto now = Clock::now();
  const bool window_end = ++tick_count_ % kTicksPerWindow == 0;
  for (auto& [name, sp] : streams_) {
    Stream& s = *sp;
    releaseStaleGap(s, name, now);
    if (settings_.nack) sendNacks(s);  // retries while no packet arrives
    const auto& dc = s.depack.counters();
    s.w_lost += dc.lost_packets - s.st.lost_packets;
    s.st.frames = dc.frames;
    s.st.frames_dropped = dc.frames_dropped;
    s.st.lost_packets = dc.lost_packets;
    s.st.bad_payload = dc.bad_payload;
    s.st.duplicates = s.reorder.duplicates();
    s.st.late = s.reorder.late();
    s.st.active = s.last_packet != Clock::time_point{} && now - s.last_packet < std::chrono::seconds(2);
    if (window_end && settings_.rtcp && s.rstats.started()) {
      const rtcp::ReportBlock b = s.rstats.report(s.ssrc, monoNowUs());
      std::vector<uint8_t> d;
      rtcp::appendReceiverReport(d, kReceiverSsrc, std::span(&b, 1));
      sendFeedback(s, d);
      ++s.st.reports_sent;
    }
    if (window_end) {
      s.st.fps_received = static_cast<double>(s.w_frames);
      s.st.fps_decoded = static_cast<double>(s.w_decoded);
      s.st.kbps = static_cast<double>(s.w_bytes) * 8.0 / 1000.0;
      const uint64_t expected = s.w_packets + s.w_lost;
      s.st.loss_pct = expected ? 100.0 * static_cast<double>(s.w_lost) / static_cast<double>(expected) : 0;
      if (s.w_latency_n) s.st.latency_ms = s.w_latency_sum / static_cast<double>(s.w_latency_n);
      std::vector<double> lat(s.latencies.begin(), s.latencies.end());
      s.st.latency_p50_ms = percentile(lat, 0.5);
      s.st.latency_p99_ms = percentile(lat, 0.99);
      s.w_bytes = s.w_frames = s.w_decoded = s.w_packets = s.w_lost = 0;
      s.w_latency_sum = 0;
      s.w_latency_n = 0;
    }
    std::lock_guard lk(mu_);
    auto& pub = published_[name];
    pub.stats = s.st;
    if (!s.sps.empty() && !s.pps.empty()) {
      pub.sps = s.sps;
      pub.pps = s.pps;
    }
  }
  tick_timer_.expires_after(kTick);
  tick_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec) tick();
  });
}

}  // namespace inspect::video
