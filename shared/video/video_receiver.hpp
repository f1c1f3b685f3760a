#pragma once
// The server's side of the camera streams: one UDP port for every robot,
// packets demultiplexed by SSRC and checked against the robot's link
// address, reordered, reassembled, decoded (libavcodec, low delay), with
// live figures per stream and keyframe requests when a picture was lost.
// Runs on a thread of its own; every public function is thread-safe.
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/udp.hpp>
#include <boost/asio/steady_timer.hpp>
#include <opencv2/core.hpp>

#include "shared/video/frame_source.hpp"
#include "shared/video/h264_codec.hpp"
#include "shared/video/rtp_h264.hpp"

namespace inspect::video {

struct ReceiverSettings {
  std::string bind = "0.0.0.0";
  uint16_t port = 5600;                 // 0 = any free port (tests)
  std::size_t reorder_window = 16;      // packets held waiting for a missing one
  double reorder_timeout_s = 0.02;      // ...and for at most this long (a gap is given up then)
  double keyframe_min_interval_s = 0.3; // at most one keyframe request per this per stream
  bool decode = true;                   // false: reassemble and count only
  /// RTCP feedback to each stream's sender (rtcp-mux, to the address its
  /// RTP comes from): a PLI with each keyframe request, a receiver report
  /// every second.
  bool rtcp = true;
  /// Repair (with rtcp): NACKs for missing packets, their RTX repairs taken
  /// in. A gap then waits for its retransmission up to about two round trips
  /// (at least reorder_timeout_s, at most max_wait_s) before it is given up.
  bool nack = true;
  double max_wait_s = 0.25;
};

/// Live figures of one stream (rates over the last second).
struct StreamStats {
  bool active = false;         // a packet arrived in the last 2 s
  uint32_t ssrc = 0;
  int width = 0, height = 0;   // of the last decoded picture
  double fps_received = 0;     // intact frames reassembled per second
  double fps_decoded = 0;
  double kbps = 0;             // RTP bytes per second x 8 / 1000
  double loss_pct = 0;         // lost / (received + lost) packets, last second
  double latency_ms = -1;      // glass-to-glass: capture -> decoded, mean of the last second; < 0 = none yet
  double latency_p50_ms = -1;  // over the last 300 decoded frames
  double latency_p99_ms = -1;
  uint64_t packets = 0, bytes = 0;
  uint64_t frames = 0, frames_dropped = 0, lost_packets = 0;
  uint64_t duplicates = 0, late = 0, bad_payload = 0;
  uint64_t decoded = 0, decode_errors = 0;
  uint64_t frames_skipped = 0; // intact frames not decoded: they follow a loss and the
                               // keyframe that repairs the picture has not come yet
  uint64_t keyframe_requests = 0;
  // RTCP feedback (ReceiverSettings::rtcp, nack):
  uint64_t nacks_sent = 0;          // NACK packets
  uint64_t nacked_packets = 0;      // sequence numbers asked for (each try)
  uint64_t retransmissions = 0;     // RTX packets that filled a hole
  uint64_t rtx_unneeded = 0;        // RTX packets for a hole already filled or given up
  uint64_t tail_probes = 0;         // NACKs of the packet after a frame's newest when its marker was late
  uint64_t plis_sent = 0;
  uint64_t reports_sent = 0;        // receiver reports
  double rtt_ms = -1;               // NACK -> its retransmission, smoothed; < 0 = none yet
};

/// Datagrams that no stream took.
struct ReceiverCounters {
  uint64_t datagrams = 0;
  uint64_t not_rtp = 0;          // parseRtp refused it (garbage)
  uint64_t rtcp = 0;             // RTCP from a sender (rtcp-mux: sender reports; not used yet)
  uint64_t wrong_payload_type = 0;
  uint64_t unknown_ssrc = 0;     // no stream has this SSRC
  uint64_t wrong_source = 0;     // right SSRC, from another address than the robot's link
  std::string last_reject;       // the latest reason, for logs
};

class VideoReceiver {
 public:
  /// Called on the receiver thread when a stream needs a keyframe (rate limited).
  using KeyframeRequest = std::function<void(const std::string& stream)>;
  /// Called on the receiver thread with each decoded picture (BGR) and its
  /// capture time on the server's clock (µs, CLOCK_MONOTONIC).
  using FrameHook = std::function<void(const std::string& stream, const cv::Mat& bgr, uint64_t capture_us)>;
  /// Called on the receiver thread with each intact access unit (before
  /// decoding; recorders store these) and its capture time on the server's clock.
  using AccessUnitHook = std::function<void(const std::string& stream, const Frame& frame, uint64_t capture_us)>;
  /// Called on the receiver thread with each accepted RTP datagram.
  using PacketHook = std::function<void(const std::string& stream, const std::vector<uint8_t>& datagram)>;

  /// Binds the port; throws VideoError naming the address and the failure.
  explicit VideoReceiver(ReceiverSettings s);
  ~VideoReceiver();
  VideoReceiver(const VideoReceiver&) = delete;
  VideoReceiver& operator=(const VideoReceiver&) = delete;

  uint16_t port() const { return port_; }
  void start();
  void stop();  // idempotent

  /// Accepts RTP with `ssrc` from `source` (the robot's link address; an
  /// unspecified address accepts any source) for stream `name`.
  /// `clock_offset_us` = server clock - sender clock (0 on one machine).
  /// Re-adding a stream with a new SSRC or source restarts its state.
  void setStream(const std::string& name, uint32_t ssrc, const boost::asio::ip::address& source,
                 int64_t clock_offset_us = 0);
  void setClockOffset(const std::string& name, int64_t clock_offset_us);
  void removeStream(const std::string& name);

  /// Hooks are set before start() (std::logic_error after): the receiver
  /// thread calls them without taking a lock.
  void setKeyframeRequest(KeyframeRequest f);
  void setFrameHook(FrameHook f);
  void setPacketHook(PacketHook f);
  void setAccessUnitHook(AccessUnitHook f);

  std::optional<StreamStats> stats(const std::string& name) const;
  ReceiverCounters counters() const;
  /// The latest decoded picture of a stream (BGR) and its capture time on the
  /// server's clock; false when none yet.
  bool latestFrame(const std::string& name, cv::Mat& bgr, uint64_t* capture_us = nullptr) const;
  /// SPS and PPS last seen on a stream (without start codes), for the SDP.
  bool parameterSets(const std::string& name, std::vector<uint8_t>& sps, std::vector<uint8_t>& pps) const;

 private:
  struct Stream;
  void doReceive();
  void onDatagram(std::size_t n);
  void handlePacket(Stream& s, const std::string& name, uint16_t seq, std::vector<uint8_t> datagram,
                    bool retransmitted = false);
  void onRtcp(std::span<const uint8_t> data);
  void onRtx(std::span<const uint8_t> data);
  void sendFeedback(Stream& s, const std::vector<uint8_t>& rtcp);
  void sendNacks(Stream& s);
  std::chrono::steady_clock::duration gapWait(const Stream& s) const;
  void checkNotStarted() const;
  /// Feeds the reorder buffer's released packets (s.ready) to the depacketizer.
  void depacketizeReady(Stream& s, const std::string& name);
  void maybeRequestKeyframe(Stream& s, const std::string& name);
  void onFrame(Stream& s, const std::string& name, const Frame& f);
  void tick();
  // Repair runs on its own short timer while a stream waits for a packet:
  // NACK retries and give-ups are due within milliseconds, not at the next tick.
  void armRepair();
  void repairTick();
  void releaseStaleGap(Stream& s, const std::string& name, std::chrono::steady_clock::time_point now);
  // When the first gap held began waiting; and giving up the gaps whose wait is over (into s.ready).
  std::chrono::steady_clock::time_point headGapSince(const Stream& s, std::chrono::steady_clock::time_point now) const;
  void giveUpStaleGaps(Stream& s, std::chrono::steady_clock::time_point now);

  ReceiverSettings settings_;
  boost::asio::io_context io_;
  boost::asio::ip::udp::socket socket_;
  boost::asio::steady_timer tick_timer_;
  boost::asio::steady_timer repair_timer_;
  bool repair_armed_ = false;
  boost::asio::ip::udp::endpoint sender_;
  std::vector<uint8_t> rx_buf_;
  uint16_t port_ = 0;
  std::thread thread_;
  bool started_ = false;

  // Set before start(), then only read (on the receiver thread).
  KeyframeRequest keyframe_request_;
  FrameHook frame_hook_;
  PacketHook packet_hook_;
  AccessUnitHook access_unit_hook_;

  // Touched only on the receiver thread (setStream/removeStream post to it).
  std::map<std::string, std::unique_ptr<Stream>> streams_;
  int tick_count_ = 0;

  // What other threads read, published by the receiver thread.
  struct Published {
    StreamStats stats;
    cv::Mat latest;  // a fresh Mat per decoded picture: readers share it safely
    uint64_t latest_capture_us = 0;
    std::vector<uint8_t> sps, pps;
  };
  mutable std::mutex mu_;
  std::map<std::string, Published> published_;
  ReceiverCounters counters_;
};

}  // namespace inspect::video
