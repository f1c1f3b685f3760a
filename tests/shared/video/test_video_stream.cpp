// The whole camera path with the real codec on loopback: VideoSender
// (synthetic source, libx264, RTP over UDP) -> optionally the test-only relay
// (tests/support/udp_relay.cpp) with loss, reordering and bursts -> VideoReceiver
// (reorder, reassemble, decode). Every decoded picture's time code is read
// back: a picture whose code does not read is a damaged picture passed on.
// Prints, per condition, frames sent / decoded / skipped, keyframe requests
// and frames until a clean picture after a loss.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <boost/asio/ip/address.hpp>

#include "shared/util/clock.hpp"
#include "shared/video/rtp_h264.hpp"
#include "shared/video/timecode.hpp"
#include "shared/video/video_receiver.hpp"
#include "shared/video/video_sender.hpp"
#include "tests/support/udp_relay.hpp"

using namespace inspect;
using namespace inspect::video;
using SteadyClock = std::chrono::steady_clock;

namespace {

constexpr const char* kStream = "robot";
constexpr uint64_t kTimecodeMask = (uint64_t{1} << 48) - 1;
constexpr auto kPoll = std::chrono::milliseconds(20);

/// Polls `pred` every 20 ms; false when it did not hold within `timeout_s`.
template <class Pred>
bool waitUntil(Pred pred, double timeout_s) {
  const auto end = SteadyClock::now() + std::chrono::duration<double>(timeout_s);
  while (!pred()) {
    if (SteadyClock::now() >= end) return false;
    std::this_thread::sleep_for(kPoll);
  }
  return true;
}

/// The RTP timestamp the sender gives a frame captured at `capture_us`.
uint32_t rtpTimestamp(uint64_t capture_us) { return static_cast<uint32_t>(capture_us * 9 / 100); }
/// RTP timestamp difference b - a (90 kHz ticks), wrap-safe.
int32_t ticksBetween(uint32_t a, uint32_t b) { return static_cast<int32_t>(b - a); }

double median(std::vector<double> v) {
  if (v.empty()) return -1;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

/// One picture the receiver's frame hook got.
struct Picture {
  uint32_t ts = 0;        // RTP timestamp (from the hook's capture time)
  int width = 0, height = 0;
  bool code_ok = false;   // time code read and equal to the capture time the hook was given
  uint32_t index = 0;     // frame index from the time code
  double latency_ms = 0;  // capture -> hook
};

/// One RTP datagram the receiver accepted (packet hook, arrival order).
struct PacketSeen {
  uint16_t seq = 0;
  uint32_t ts = 0;
  bool marker = false;
  uint64_t arrival_us = 0;  // monoNowUs() in the packet hook
};

/// How the picture came back after losses.
struct Recovery {
  int episodes = 0;        // losses ended by a decoded picture
  int max_frames = 0;      // frames produced from an episode's first lost packet to the next decoded picture
  bool never = false;      // a loss more than kRecoveryWindowS before the end was never followed by a picture
  bool pending = false;    // the same, for a loss closer to the end (no time to recover)
  double detect_ms = -1;   // median over episodes: packet after the first gap arrives -> next keyframe request
};

/// Time a loss is given to end in a picture before the run's end. At 10 %
/// packet loss an IDR of about ten packets arrives whole only about a third of
/// the time and requests go out at most every 300 ms, so healthy runs have
/// episodes of up to 40 frames (1.3 s, measured over 11 runs); at 1 s one
/// run in about ten of the sanitizer build ended flagged.
constexpr double kRecoveryWindowS = 2.0;

/// Finds the lost packets (sequence numbers never seen) and, for each loss
/// episode, the frames between its first lost packet and the next picture.
Recovery analyseRecovery(const std::vector<PacketSeen>& arrivals, const std::vector<Picture>& pictures,
                         const std::vector<uint64_t>& requests_us, double fps) {
  Recovery r;
  if (arrivals.empty()) return r;
  const double tick = kClockRate / fps;
  std::map<int64_t, PacketSeen> by_seq;  // extended sequence numbers
  int64_t ext = arrivals.front().seq;
  for (const auto& p : arrivals) {
    ext += static_cast<int16_t>(static_cast<uint16_t>(p.seq - static_cast<uint16_t>(ext)));
    by_seq.emplace(ext, p);
  }
  const uint32_t end_ts = by_seq.rbegin()->second.ts;
  std::ptrdiff_t episode_picture = -1;
  std::vector<double> detect;
  for (auto it = by_seq.begin(), next = std::next(it); next != by_seq.end(); ++it, ++next) {
    if (next->first - it->first == 1) continue;
    // The first missing packet belongs to the frame of the one before it,
    // or (after a marker) to a later frame, at most the one after the gap.
    const PacketSeen& before = it->second;
    uint32_t lost_ts = before.ts;
    if (before.marker) {
      lost_ts = before.ts + static_cast<uint32_t>(std::lround(tick));
      if (ticksBetween(lost_ts, next->second.ts) < 0) lost_ts = next->second.ts;
    }
    const auto pic = std::find_if(pictures.begin(), pictures.end(),
                                  [&](const Picture& p) { return ticksBetween(lost_ts, p.ts) > 0; });
    if (pic == pictures.end()) {
      (ticksBetween(lost_ts, end_ts) > static_cast<int32_t>(kRecoveryWindowS * kClockRate) ? r.never : r.pending) =
          true;
      break;  // no picture after this one either
    }
    if (pic - pictures.begin() == episode_picture) continue;  // the same episode
    episode_picture = pic - pictures.begin();
    ++r.episodes;
    const uint64_t seen = next->second.arrival_us;
    const auto req = std::lower_bound(requests_us.begin(), requests_us.end(), seen);
    if (req != requests_us.end()) detect.push_back(static_cast<double>(*req - seen) / 1000.0);
    r.max_frames = std::max(r.max_frames, static_cast<int>(std::lround(ticksBetween(lost_ts, pic->ts) / tick)));
  }
  r.detect_ms = median(detect);
  return r;
}

/// What one run gave, after the sender stopped and the receiver drained.
struct Summary {
  SenderStats sender;
  StreamStats stream;
  ReceiverCounters counters;
  std::vector<Picture> pictures;
  uint64_t damaged = 0;        // the time code did not read back: must stay 0
  uint64_t out_of_order = 0;   // frame index or timestamp not increasing
  uint64_t unknown_index = 0;  // a frame index the sender never produced
  double latency_p50_ms = -1;  // over every picture the hook got
  double stream_s = 0;         // first to last packet, stream time
  Recovery recovery;
  bool drained = false;
};

/// Serves keyframe requests a little late on a thread of its own, standing
/// for the TCP hop from the server to the robot (the receiver thread must not wait).
class DelayedRequests {
 public:
  DelayedRequests(VideoSender& sender, std::chrono::milliseconds delay)
      : sender_(sender), delay_(delay), thread_([this] { run(); }) {}
  ~DelayedRequests() {
    {
      std::lock_guard lk(mu_);
      stop_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  DelayedRequests(const DelayedRequests&) = delete;
  DelayedRequests& operator=(const DelayedRequests&) = delete;

  void post() {
    {
      std::lock_guard lk(mu_);
      due_.push_back(SteadyClock::now() + delay_);
    }
    cv_.notify_all();
  }

 private:
  void run() {
    std::unique_lock lk(mu_);
    while (!stop_) {
      if (due_.empty()) {
        cv_.wait_for(lk, std::chrono::milliseconds(200));
      } else if (SteadyClock::now() < due_.front()) {
        cv_.wait_until(lk, due_.front());
      } else {
        due_.pop_front();
        lk.unlock();
        sender_.requestKeyframe();
        lk.lock();
      }
    }
  }

  VideoSender& sender_;
  const std::chrono::milliseconds delay_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<SteadyClock::time_point> due_;
  bool stop_ = false;
  std::thread thread_;  // last: starts after the rest is built
};

enum class Requests { kIgnored, kServed, kServedLate };

struct RigOptions {
  int width = 320, height = 240;
  double fps = 30.0;
  int gop = 30;
  int bitrate_kbps = 1000;  // below ~500 at 320x240 the first IDR is too coarse for its time code to read
  std::string preset = "ultrafast";
  Requests requests = Requests::kServed;
  std::optional<test::UdpRelayParams> relay;  // none: the sender sends straight to the receiver
  std::size_t reorder_window = 16;  // the receiver's (packets)
  bool nack = false;  // RTCP feedback and retransmission (off: the keyframe-only repair these tests measure)
};

/// 640x480 at 2 Mbit/s (the robot's defaults), straight to the receiver.
RigOptions vgaOptions() {
  RigOptions o;
  o.width = 640;
  o.height = 480;
  o.bitrate_kbps = 2000;
  return o;
}

/// Receiver on 127.0.0.1:ephemeral, the relay (optional) and a sender aimed
/// at it, with hooks that record every accepted packet and decoded picture.
class StreamRig {
 public:
  explicit StreamRig(const RigOptions& o) : o_(o) {
    ReceiverSettings rs;
    rs.bind = "127.0.0.1";
    rs.port = 0;
    rs.reorder_window = o.reorder_window;
    rs.nack = o.nack;
    rs.rtcp = o.nack;
    receiver_ = std::make_unique<VideoReceiver>(rs);
    uint16_t dest = receiver_->port();
    if (o.relay) {
      relay_ = std::make_unique<test::UdpRelay>(dest, *o.relay);
      dest = relay_->port();
    }
    SenderSettings ss;
    ss.source.width = o.width;
    ss.source.height = o.height;
    ss.source.fps = o.fps;
    ss.encoder.gop = o.gop;
    ss.encoder.bitrate_kbps = o.bitrate_kbps;
    ss.encoder.preset = o.preset;
    ss.host = "127.0.0.1";
    ss.port = dest;
    ss.retransmission = o.nack;
    sender_ = std::make_unique<VideoSender>(ss);
    if (o.requests == Requests::kServedLate)
      late_ = std::make_unique<DelayedRequests>(*sender_, std::chrono::milliseconds(10));
    receiver_->setStream(kStream, sender_->ssrc(), boost::asio::ip::make_address("127.0.0.1"));
    receiver_->setKeyframeRequest([this](const std::string&) {
      {
        std::lock_guard lk(mu_);
        requests_.push_back(monoNowUs());
      }
      if (o_.requests == Requests::kServed) sender_->requestKeyframe();
      if (late_) late_->post();
    });
    receiver_->setPacketHook([this](const std::string&, const std::vector<uint8_t>& d) {
      RtpPacket p;
      if (parseRtp(d, p) != RtpError::kNone) return;
      std::lock_guard lk(mu_);
      packets_.push_back({p.seq, p.timestamp, p.marker, monoNowUs()});
    });
    receiver_->setFrameHook([this](const std::string&, const cv::Mat& bgr, uint64_t capture_us) {
      Picture p;
      p.ts = rtpTimestamp(capture_us);
      p.width = bgr.cols;
      p.height = bgr.rows;
      p.latency_ms = (static_cast<double>(monoNowUs()) - static_cast<double>(capture_us)) / 1000.0;
      const auto code = readTimecode(bgr);
      p.code_ok = code && code->capture_us == (capture_us & kTimecodeMask);
      p.index = code ? code->frame_index : 0;
      std::lock_guard lk(mu_);
      pictures_.push_back(p);
    });
    receiver_->start();
  }

  ~StreamRig() {
    receiver_->stop();  // no more callbacks into the sender
    sender_->stop();
    late_.reset();
  }
  StreamRig(const StreamRig&) = delete;
  StreamRig& operator=(const StreamRig&) = delete;

  void start() { sender_->start(); }

  /// Lets the stream run `seconds`, calling `each_poll` every 20 ms.
  void runFor(double seconds, const std::function<void()>& each_poll = {}) {
    const auto end = SteadyClock::now() + std::chrono::duration<double>(seconds);
    while (SteadyClock::now() < end) {
      if (each_poll) each_poll();
      std::this_thread::sleep_for(kPoll);
    }
  }

  /// Stops the sender, waits (bounded) until the receiver took and published
  /// everything, and sums the run up.
  Summary finish() {
    sender_->stop();
    Summary s;
    std::size_t last = packetCount();
    auto stable_since = SteadyClock::now();
    s.drained = waitUntil(
        [&] {
          const std::size_t n = packetCount();
          if (n != last) {
            last = n;
            stable_since = SteadyClock::now();
          }
          const auto st = receiver_->stats(kStream);
          return SteadyClock::now() - stable_since > std::chrono::milliseconds(300) && st && st->packets == n &&
                 st->decoded == pictureCount();
        },
        5.0);
    s.sender = sender_->stats();
    s.stream = receiver_->stats(kStream).value_or(StreamStats{});
    s.counters = receiver_->counters();
    std::vector<PacketSeen> packets;
    std::vector<uint64_t> requests;
    {
      std::lock_guard lk(mu_);
      s.pictures = pictures_;
      packets = packets_;
      requests = requests_;
    }
    std::vector<double> latencies;
    for (std::size_t i = 0; i < s.pictures.size(); ++i) {
      const Picture& p = s.pictures[i];
      latencies.push_back(p.latency_ms);
      if (!p.code_ok) ++s.damaged;
      if (p.code_ok && p.index >= s.sender.captured) ++s.unknown_index;
      if (i > 0 && (p.index <= s.pictures[i - 1].index || ticksBetween(s.pictures[i - 1].ts, p.ts) <= 0))
        ++s.out_of_order;
    }
    s.latency_p50_ms = median(latencies);
    if (!packets.empty()) s.stream_s = ticksBetween(packets.front().ts, packets.back().ts) / double(kClockRate);
    s.recovery = analyseRecovery(packets, s.pictures, requests, o_.fps);
    return s;
  }

  VideoSender& sender() { return *sender_; }
  VideoReceiver& receiver() { return *receiver_; }
  const test::UdpRelay* relay() const { return relay_.get(); }
  std::size_t pictureCount() const {
    std::lock_guard lk(mu_);
    return pictures_.size();
  }
  std::size_t packetCount() const {
    std::lock_guard lk(mu_);
    return packets_.size();
  }
  /// Pictures from the `from`th on that are `w` x `h` with a readable time code.
  std::size_t countShowing(std::size_t from, int w, int h) const {
    std::lock_guard lk(mu_);
    return static_cast<std::size_t>(std::count_if(
        pictures_.begin() + static_cast<std::ptrdiff_t>(std::min(from, pictures_.size())), pictures_.end(),
        [&](const Picture& p) { return p.width == w && p.height == h && p.code_ok; }));
  }

 private:
  RigOptions o_;
  std::unique_ptr<VideoReceiver> receiver_;
  std::unique_ptr<test::UdpRelay> relay_;
  std::unique_ptr<VideoSender> sender_;
  std::unique_ptr<DelayedRequests> late_;
  mutable std::mutex mu_;
  std::vector<PacketSeen> packets_;
  std::vector<Picture> pictures_;
  std::vector<uint64_t> requests_;  // monoNowUs() of each keyframe request
};

std::string recoveryText(const Recovery& r) {
  if (r.never) return "never";
  if (r.episodes == 0) return r.pending ? "pending" : "-";
  return std::to_string(r.max_frames) + (r.pending ? "+pend" : "");
}

double requestsPerMinute(const Summary& s) {
  return s.stream_s > 0 ? static_cast<double>(s.stream.keyframe_requests) * 60.0 / s.stream_s : 0;
}

void printHeader() {
  std::printf("%-26s %5s %7s %7s %7s %6s %10s %4s %12s %7s %7s %7s %9s\n", "condition", "sent", "decoded", "skipped",
              "lost_pk", "kf_req", "kf req/min", "IDRs", "max to clean", "p50 ms", "damaged", "packets",
              "detect ms");
}

void printRow(const std::string& condition, const Summary& s) {
  std::printf("%-26s %5lu %7lu %7lu %7lu %6lu %10.1f %4lu %12s %7.1f %7lu %7lu %9.1f\n", condition.c_str(),
              static_cast<unsigned long>(s.sender.encoded), static_cast<unsigned long>(s.stream.decoded),
              static_cast<unsigned long>(s.stream.frames_skipped), static_cast<unsigned long>(s.stream.lost_packets),
              static_cast<unsigned long>(s.stream.keyframe_requests), requestsPerMinute(s),
              static_cast<unsigned long>(s.sender.keyframes), recoveryText(s.recovery).c_str(), s.latency_p50_ms,
              static_cast<unsigned long>(s.damaged), static_cast<unsigned long>(s.stream.packets),
              s.recovery.detect_ms);
  std::fflush(stdout);
}

/// What every run must give, whatever the network did.
void expectSound(const Summary& s, const std::string& condition) {
  EXPECT_TRUE(s.drained) << condition << ": the receiver did not settle within 5 s after the sender stopped";
  EXPECT_EQ(s.damaged, 0u) << condition << ": pictures whose time code did not read back (damaged) out of "
                           << s.pictures.size();
  EXPECT_EQ(s.out_of_order, 0u) << condition;
  EXPECT_EQ(s.unknown_index, 0u) << condition;
  EXPECT_EQ(s.stream.decoded, s.pictures.size()) << condition;
  EXPECT_LE(s.stream.decoded, s.sender.encoded) << condition;
}

// --------------------------------------------------------- raw datagrams

/// A UDP socket bound to `ip`:0 that sends to 127.0.0.1:`port`; fd < 0 when the bind failed.
struct RawSender {
  RawSender(const char* ip, uint16_t port) : to(test::loopbackAddress(port)) {
    fd = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    ::inet_pton(AF_INET, ip, &a.sin_addr);
    if (fd >= 0 && ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
      ::close(fd);
      fd = -1;
    }
  }
  ~RawSender() {
    if (fd >= 0) ::close(fd);
  }
  RawSender(const RawSender&) = delete;
  RawSender& operator=(const RawSender&) = delete;

  void send(const std::vector<uint8_t>& d) const {
    ::sendto(fd, d.data(), d.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  int fd = -1;
  sockaddr_in to;
};

/// An RTP datagram: 12-byte header (no CSRC, no extension) and a P-slice-like payload.
std::vector<uint8_t> rtpDatagram(uint8_t version, uint8_t payload_type, uint32_t ssrc, uint16_t seq) {
  std::vector<uint8_t> d = {static_cast<uint8_t>(version << 6), payload_type, static_cast<uint8_t>(seq >> 8),
                            static_cast<uint8_t>(seq), 0, 0, 0x10, 0,
                            static_cast<uint8_t>(ssrc >> 24), static_cast<uint8_t>(ssrc >> 16),
                            static_cast<uint8_t>(ssrc >> 8), static_cast<uint8_t>(ssrc),
                            0x41, 0x9A, 0x02, 0x04, 0x08, 0x10};
  return d;
}

}  // namespace

// ------------------------------------------------------------------ tests

TEST(VideoStreamClean, DecodesNearlyEveryFrameWithTimecodeSizeAndLatency) {
  StreamRig rig(vgaOptions());
  rig.start();
  rig.runFor(2.0);
  const Summary s = rig.finish();
  // The receiver publishes the latency percentiles once a second.
  std::optional<StreamStats> st;
  EXPECT_TRUE(waitUntil(
      [&] {
        st = rig.receiver().stats(kStream);
        return st && st->latency_p50_ms > 0;
      },
      3.0))
      << "no latency p50 published";
  printHeader();
  printRow("clean 640x480", s);
  std::printf("packets %lu, bytes %lu, receiver p50 %.1f ms p99 %.1f ms, decode errors %lu\n",
              static_cast<unsigned long>(s.stream.packets), static_cast<unsigned long>(s.stream.bytes),
              st ? st->latency_p50_ms : -1.0, st ? st->latency_p99_ms : -1.0,
              static_cast<unsigned long>(s.stream.decode_errors));

  expectSound(s, "clean");
  // About 60 in 2 s; "almost nothing" is under 10 (the sanitizer stage, four
  // test programs on 2 cores, encoded 21 in one clean-clone run).
  ASSERT_GT(s.sender.encoded, 10u) << "the sender produced almost nothing in 2 s";
  EXPECT_GE(static_cast<double>(s.stream.decoded), 0.9 * static_cast<double>(s.sender.encoded));
  EXPECT_EQ(s.stream.lost_packets, 0u);
  EXPECT_EQ(s.stream.frames_dropped, 0u);
  EXPECT_EQ(s.stream.decode_errors, 0u);
  EXPECT_EQ(s.sender.send_errors, 0u);
  ASSERT_TRUE(st.has_value());
  EXPECT_TRUE(std::isfinite(st->latency_p50_ms));
  EXPECT_GT(st->latency_p50_ms, 0.0);
  EXPECT_GT(s.latency_p50_ms, 0.0);
  EXPECT_EQ(st->width, 640);
  EXPECT_EQ(st->height, 480);
  ASSERT_FALSE(s.pictures.empty());
  for (const auto& p : s.pictures) {
    EXPECT_EQ(p.width, 640);
    EXPECT_EQ(p.height, 480);
  }
}

namespace {

/// A 4 s stream at 320x240 with GOP 300 through a relay that loses 25
/// packets in a row after about a second.
Summary burstRun(Requests requests, std::size_t reorder_window, uint64_t* keyframes_before_burst) {
  RigOptions o;
  o.gop = 300;
  o.requests = requests;
  o.reorder_window = reorder_window;
  test::UdpRelayParams rp;
  rp.seed = 11;
  rp.burst_from = 120;
  rp.burst_len = 25;
  o.relay = rp;
  StreamRig rig(o);
  rig.start();
  rig.runFor(4.0, [&] {
    if (rig.relay()->counters().dropped == 0) *keyframes_before_burst = rig.sender().stats().keyframes;
  });
  EXPECT_EQ(rig.relay()->counters().dropped, rp.burst_len) << "the burst did not happen within the run";
  return rig.finish();
}

}  // namespace

TEST(VideoStreamKeyframes, RequestsServedRecoverTheBurstQuickly) {
  uint64_t served_before = 0, ignored_before = 0, small_window_before = 0;
  const Summary served = burstRun(Requests::kServed, 16, &served_before);
  const Summary ignored = burstRun(Requests::kIgnored, 16, &ignored_before);
  // For comparison: how much of the recovery is the reorder buffer holding the gap.
  const Summary small_window = burstRun(Requests::kServed, 4, &small_window_before);
  std::printf("GOP 300 (an IDR every 10 s), 4 s at 320x240, 25 packets lost in a row after ~1 s\n"
              "(detect ms: the packet after the gap arrives -> the receiver asks for a keyframe)\n");
  printHeader();
  printRow("requests served", served);
  printRow("requests ignored", ignored);
  printRow("served, reorder window 4", small_window);
  std::printf("IDRs before the burst: served %lu, ignored %lu\n", static_cast<unsigned long>(served_before),
              static_cast<unsigned long>(ignored_before));

  expectSound(served, "served");
  expectSound(ignored, "ignored");
  expectSound(small_window, "served, reorder window 4");
  EXPECT_GT(served.sender.keyframes, served_before) << "no IDR after the burst although requests were served";
  EXPECT_GE(served.recovery.episodes, 1);
  EXPECT_FALSE(served.recovery.never);
  EXPECT_LE(served.recovery.max_frames, 30) << "more than a second to a clean picture with requests served";
  EXPECT_GT(served.stream.keyframe_requests, 0u);
  // Without requests served the picture stays frozen until the next periodic IDR (10 s away).
  EXPECT_EQ(ignored.sender.keyframes, ignored_before);
  EXPECT_TRUE(ignored.recovery.never);
  EXPECT_EQ(ignored.recovery.episodes, 0);
  EXPECT_GT(ignored.stream.frames_skipped, 0u);
  EXPECT_GT(served.stream.decoded, ignored.stream.decoded);
}

TEST(VideoStreamLoss, RealCodecThroughLossNeverPassesDamagedPictures) {
  struct Case {
    const char* name;
    test::UdpRelayParams p;
    double min_decoded;  // fraction of the frames sent
  };
  const Case cases[] = {
      // Floors well below what was measured (1 %: 75-81 %, 5 %: 30-54 %, 10 %: 14-34 %, burst: 88 %):
      // each loss freezes the picture until an IDR, requests come at most every 0.3 s and a
      // gap is only given up after 16 more packets (~170 ms here), so the spread is wide.
      {"1% loss, 5% reorder", {0.01, 0.0, 0.05, 0.0, 21}, 0.5},
      {"5% loss, 5% reorder", {0.05, 0.0, 0.05, 0.0, 22}, 0.15},
      {"10% loss, 5% reorder", {0.10, 0.0, 0.05, 0.0, 23}, 0.05},
      {"burst 30 pk, 5% reorder", {0.0, 0.0, 0.05, 0.0, 24, 150, 30}, 0.6},
  };
  std::printf("320x240 @ 30 fps, GOP 30, 4 s per condition; keyframe requests served 10 ms late\n");
  printHeader();
  for (const auto& c : cases) {
    RigOptions o;
    o.requests = Requests::kServedLate;
    o.relay = c.p;
    StreamRig rig(o);
    rig.start();
    rig.runFor(4.0);
    const Summary s = rig.finish();
    printRow(c.name, s);
    if (s.damaged > 0)
      std::printf("  DAMAGED: %lu of %zu pictures (%.2f %%)\n", static_cast<unsigned long>(s.damaged),
                  s.pictures.size(), 100.0 * static_cast<double>(s.damaged) / static_cast<double>(s.pictures.size()));

    expectSound(s, c.name);
    EXPECT_GT(static_cast<double>(s.stream.decoded), c.min_decoded * static_cast<double>(s.sender.encoded)) << c.name;
    EXPECT_GT(s.stream.lost_packets, 0u) << c.name;
    // At most one request per 300 ms (plus the first).
    EXPECT_LE(static_cast<double>(s.stream.keyframe_requests), s.stream_s / 0.3 + 1.0) << c.name;
    EXPECT_GE(s.recovery.episodes, 1) << c.name;
    EXPECT_FALSE(s.recovery.never) << c.name << ": a loss was never followed by a clean picture";
  }
}

// NACK + RTX through a relay that loses 10 % both ways (RTCP too) with 10 ms
// of one-way delay: the same stream with and without retransmission.
TEST(VideoStreamLoss, RetransmissionRepairsRandomLossWithoutKeyframes) {
  std::printf("320x240 @ 30 fps, GOP 30, 4 s, 10 %% loss both ways, 10 ms one-way delay\n");
  printHeader();
  Summary runs[2];
  for (int nack = 0; nack < 2; ++nack) {
    RigOptions o;
    o.requests = Requests::kServedLate;
    test::UdpRelayParams rp;
    rp.drop = 0.10;
    rp.delay_ms = 10;
    rp.seed = 31;
    o.relay = rp;
    o.nack = nack == 1;
    StreamRig rig(o);
    rig.start();
    rig.runFor(4.0);
    runs[nack] = rig.finish();
    printRow(nack ? "10% loss, NACK + RTX" : "10% loss, keyframes only", runs[nack]);
    expectSound(runs[nack], nack ? "NACK" : "keyframes only");
    EXPECT_GT(rig.relay()->counters().dropped, 0u);
    if (nack) {
      EXPECT_GT(rig.relay()->counters().back_received, 0u) << "no RTCP feedback went back";
    }
  }
  const Summary& with = runs[1];
  std::printf("NACK: %lu NACKs for %lu packets, %lu retransmissions taken, %lu unneeded, RTT %.1f ms; sender sent %lu RTX\n",
              static_cast<unsigned long>(with.stream.nacks_sent), static_cast<unsigned long>(with.stream.nacked_packets),
              static_cast<unsigned long>(with.stream.retransmissions),
              static_cast<unsigned long>(with.stream.rtx_unneeded), with.stream.rtt_ms,
              static_cast<unsigned long>(with.sender.retransmitted));
  EXPECT_GT(with.stream.retransmissions, 0u);
  EXPECT_GT(with.sender.retransmitted, 0u);
  EXPECT_GT(with.stream.decoded, runs[0].stream.decoded) << "retransmission did not show more pictures";
  // Floor well below the measured figure (the benchmark has the real one).
  EXPECT_GT(static_cast<double>(with.stream.decoded), 0.7 * static_cast<double>(with.sender.encoded));
}

TEST(VideoStreamBadInput, GarbageAndForeignPacketsAreCountedExactlyAndIgnored) {
  StreamRig rig(RigOptions{});
  rig.start();
  ASSERT_TRUE(waitUntil([&] { return rig.pictureCount() >= 10; }, 5.0)) << "the clean stream did not start";
  const uint32_t ssrc = rig.sender().ssrc();
  const uint16_t port = rig.receiver().port();
  const RawSender local("127.0.0.1", port);
  ASSERT_GE(local.fd, 0);
  RawSender foreign("127.0.0.2", port);
  if (foreign.fd < 0) {
    // No 127.0.0.2 here: a second stream expects another SSRC from 127.0.0.2, sent from 127.0.0.1.
    rig.receiver().setStream("other", ssrc ^ 0x5A5A5A5A, boost::asio::ip::make_address("127.0.0.2"));
  }
  const uint32_t foreign_ssrc = foreign.fd >= 0 ? ssrc : ssrc ^ 0x5A5A5A5A;
  const RawSender& foreign_tx = foreign.fd >= 0 ? foreign : local;
  const std::size_t pictures_before = rig.pictureCount();

  std::mt19937 rng(7);
  std::uniform_int_distribution<int> byte(0, 255);
  ReceiverCounters want;
  for (int i = 0; i < 20; ++i) {  // random bytes, RTP version 0 or 3
    std::vector<uint8_t> d(std::uniform_int_distribution<std::size_t>(12, 1400)(rng));
    for (auto& b : d) b = static_cast<uint8_t>(byte(rng));
    d[0] = static_cast<uint8_t>((d[0] & 0x3F) | (i % 2 ? 0xC0 : 0x00));
    local.send(d);
    ++want.not_rtp;
  }
  for (std::size_t n = 0; n < kRtpHeaderSize; ++n) {  // too short for an RTP header, the empty datagram too
    std::vector<uint8_t> d(n, 0x80);
    local.send(d);
    ++want.not_rtp;
  }
  for (int i = 0; i < 5; ++i) {  // RTP version 1
    local.send(rtpDatagram(1, kPayloadType, ssrc, static_cast<uint16_t>(i)));
    ++want.not_rtp;
  }
  {  // version 2 with 15 CSRCs announced and none there
    auto d = rtpDatagram(2, kPayloadType, ssrc, 1);
    d[0] |= 0x0F;
    local.send(d);
    ++want.not_rtp;
  }
  for (const int pt : {0, 8, 97, 127, 0x80 | 97}) {  // wrong payload type, our SSRC
    local.send(rtpDatagram(2, static_cast<uint8_t>(pt), ssrc, 7));
    ++want.wrong_payload_type;
  }
  for (int i = 0; i < 6; ++i) {  // SSRCs no stream has
    local.send(rtpDatagram(2, kPayloadType, ssrc + 1 + static_cast<uint32_t>(i), 9));
    ++want.unknown_ssrc;
  }
  for (int i = 0; i < 7; ++i) {  // the stream's SSRC from another address
    foreign_tx.send(rtpDatagram(2, kPayloadType, foreign_ssrc, static_cast<uint16_t>(100 + i)));
    ++want.wrong_source;
  }
  const auto matches = [&](const ReceiverCounters& c) {
    return c.not_rtp == want.not_rtp && c.wrong_payload_type == want.wrong_payload_type &&
           c.unknown_ssrc == want.unknown_ssrc && c.wrong_source == want.wrong_source;
  };
  EXPECT_TRUE(waitUntil([&] { return matches(rig.receiver().counters()); }, 3.0));
  // The stream keeps decoding (and nothing more gets counted meanwhile).
  EXPECT_TRUE(waitUntil([&] { return rig.pictureCount() >= pictures_before + 20; }, 5.0))
      << "the stream stopped decoding after the bad input";
  const Summary s = rig.finish();
  std::printf("%s sent from 127.0.0.2; counters: not_rtp %lu, wrong_payload_type %lu, unknown_ssrc %lu, "
              "wrong_source %lu; last reject: %s\n",
              foreign.fd >= 0 ? "stream SSRC" : "fallback: 127.0.0.1 for a stream expecting 127.0.0.2,",
              static_cast<unsigned long>(s.counters.not_rtp), static_cast<unsigned long>(s.counters.wrong_payload_type),
              static_cast<unsigned long>(s.counters.unknown_ssrc), static_cast<unsigned long>(s.counters.wrong_source),
              s.counters.last_reject.c_str());
  EXPECT_EQ(s.counters.not_rtp, want.not_rtp);
  EXPECT_EQ(s.counters.wrong_payload_type, want.wrong_payload_type);
  EXPECT_EQ(s.counters.unknown_ssrc, want.unknown_ssrc);
  EXPECT_EQ(s.counters.wrong_source, want.wrong_source);
  expectSound(s, "bad input");
  EXPECT_EQ(s.stream.lost_packets, 0u);
  EXPECT_EQ(s.stream.late, 0u);
  EXPECT_EQ(s.stream.duplicates, 0u);
  EXPECT_EQ(s.stream.bad_payload, 0u);
  EXPECT_EQ(s.stream.decode_errors, 0u);
  EXPECT_EQ(s.stream.packets, s.sender.packets) << "a foreign datagram entered the stream, or one of ours was lost";
}

// A capture time at the end of the clock (a damaged or forged header
// extension) plus the stream's clock offset wraps instead of overflowing a
// signed integer (undefined behaviour, caught by the sanitizer build's
// UBSan; found while writing tests/fuzz/fuzz_rtp_h264).
TEST(VideoStreamBadInput, CaptureTimeAtTheEndOfTheClockWrapsWithTheOffset) {
  ReceiverSettings rs;
  rs.bind = "127.0.0.1";
  rs.port = 0;
  rs.decode = false;
  VideoReceiver rx(rs);
  constexpr uint32_t kSsrc = 0x00C0FFEE;
  constexpr int64_t kOffset = 5'000'000;
  constexpr uint64_t kCapture = 0x7FFF'FFFF'FFFF'FFFFull;
  rx.setStream(kStream, kSsrc, boost::asio::ip::make_address("127.0.0.1"), kOffset);
  std::mutex mu;
  std::vector<uint64_t> captures;
  rx.setAccessUnitHook([&](const std::string&, const Frame&, uint64_t capture_us) {
    std::lock_guard lk(mu);
    captures.push_back(capture_us);
  });
  rx.start();
  const RawSender tx("127.0.0.1", rx.port());
  ASSERT_GE(tx.fd, 0);
  H264Packetizer pk(kSsrc, 1200);
  std::vector<std::vector<uint8_t>> packets;
  const uint8_t access_unit_delimiter[] = {0, 0, 0, 1, 0x09, 0xF0};
  pk.packetize(access_unit_delimiter, 0, kCapture, packets);
  ASSERT_EQ(packets.size(), 1u);
  tx.send(packets[0]);
  EXPECT_TRUE(waitUntil(
      [&] {
        std::lock_guard lk(mu);
        return !captures.empty();
      },
      3.0));
  rx.stop();
  std::lock_guard lk(mu);
  ASSERT_EQ(captures.size(), 1u);
  EXPECT_EQ(captures[0], kCapture + static_cast<uint64_t>(kOffset));
}

TEST(VideoStreamSettings, SizeChangeMidStreamIsFollowedAndBadValuesRefused) {
  StreamRig rig(vgaOptions());
  rig.start();
  // At least 10 pictures of that size since the change, and the receiver's figures say so.
  const auto showing = [&](int w, int h, std::size_t since) {
    return waitUntil(
        [&] {
          return rig.countShowing(since, w, h) >= 10 &&
                 rig.receiver().stats(kStream).value_or(StreamStats{}).width == w;
        },
        5.0);
  };
  ASSERT_TRUE(showing(640, 480, 0)) << "no 640x480 picture";

  const auto size = [](std::optional<int> w, std::optional<int> h) {
    SenderChange c;
    c.width = w;
    c.height = h;
    return c;
  };
  SenderChange no_fps, low_bitrate;
  no_fps.fps = 0.0;
  low_bitrate.bitrate_kbps = 10;
  struct Bad {
    const char* field;  // the message must name it
    SenderChange change;
  };
  const Bad bads[] = {
      {"width", size(321, 240)}, {"height", size(320, 241)},        {"width", size(320, std::nullopt)},
      {"fps", no_fps},           {"bitrate_kbps", low_bitrate},     {"width", size(8, 8)},
  };
  for (const auto& b : bads) {
    const std::string why = rig.sender().apply(b.change);
    EXPECT_NE(why.find(b.field), std::string::npos) << "apply() said '" << why << "', expected it to name " << b.field;
  }
  EXPECT_EQ(rig.sender().stats().width, 640) << "a refused change was applied";

  std::size_t since = rig.pictureCount();
  EXPECT_EQ(rig.sender().apply(size(320, 240)), "");
  EXPECT_TRUE(showing(320, 240, since)) << "the receiver's picture did not follow to 320x240";
  since = rig.pictureCount();
  EXPECT_EQ(rig.sender().apply(size(640, 480)), "");
  EXPECT_TRUE(showing(640, 480, since)) << "the receiver's picture did not follow back to 640x480";
  const Summary s = rig.finish();
  int size_changes = 0;
  for (std::size_t i = 1; i < s.pictures.size(); ++i)
    size_changes += s.pictures[i].width != s.pictures[i - 1].width ? 1 : 0;
  std::printf("sizes followed; %zu pictures, %d size changes, %lu IDRs, decode errors %lu, lost %lu; "
              "sender captured %lu, encoded %lu, dropped %lu\n",
              s.pictures.size(), size_changes, static_cast<unsigned long>(s.sender.keyframes),
              static_cast<unsigned long>(s.stream.decode_errors), static_cast<unsigned long>(s.stream.lost_packets),
              static_cast<unsigned long>(s.sender.captured), static_cast<unsigned long>(s.sender.encoded),
              static_cast<unsigned long>(s.sender.dropped));
  expectSound(s, "size change");
  EXPECT_EQ(size_changes, 2) << "pictures of the old size after the new one";
  EXPECT_EQ(s.stream.lost_packets, 0u);
  EXPECT_EQ(s.stream.decode_errors, 0u);
  EXPECT_GE(s.sender.keyframes, 3u) << "each size change starts with an IDR";
}

TEST(VideoStreamOverload, SenderDropsFramesInsteadOfQueueing) {
  RigOptions o;
  o.width = 1280;
  o.height = 720;
  o.fps = 120;
  o.preset = "veryfast";
  o.bitrate_kbps = 8000;
  StreamRig rig(o);
  rig.start();
  rig.runFor(3.0);
  const Summary s = rig.finish();
  const std::size_t n = s.pictures.size();
  std::vector<double> last;
  for (std::size_t i = n > 30 ? n - 30 : 0; i < n; ++i) last.push_back(s.pictures[i].latency_ms);
  std::printf("1280x720 @ 120 fps veryfast: captured %lu, encoded %lu, dropped %lu, encode %.1f ms; "
              "decoded %lu; latency p50 %.1f ms (receiver %.1f), last 30 frames median %.1f ms\n",
              static_cast<unsigned long>(s.sender.captured), static_cast<unsigned long>(s.sender.encoded),
              static_cast<unsigned long>(s.sender.dropped), s.sender.encode_ms,
              static_cast<unsigned long>(s.stream.decoded), s.latency_p50_ms, s.stream.latency_p50_ms, median(last));
  expectSound(s, "overload");
  EXPECT_GT(s.sender.dropped, 0u) << "the encoder kept up: no overload to test";
  // Every captured picture was encoded or dropped, but for one left in the mailbox at stop.
  EXPECT_GE(s.sender.captured, s.sender.encoded + s.sender.dropped);
  EXPECT_LE(s.sender.captured, s.sender.encoded + s.sender.dropped + 1);
  ASSERT_GT(n, 30u);
#ifndef INSPECT_SANITIZED
  // Under ASan the receiver's own instrumented code cannot decode 720p at 120
  // fps either, and queues in its socket buffer (latency p50 279 ms, last 30
  // frames 539 ms measured there): the sender's behaviour above is what the
  // sanitizer build checks, the latency bound is the optimised build's.
  EXPECT_LT(s.latency_p50_ms, 500.0);
  EXPECT_LT(median(last), 500.0) << "latency grew towards the end";
#endif
}
