#pragma once
// The robot's camera stream: capture -> H.264 encode -> RTP -> UDP, on two
// threads of its own so that the 100 Hz control loop never waits for video.
//
// The capture thread paces the source at the frame rate (a camera paces
// itself) and leaves each picture in a one-slot mailbox; the encode thread
// takes the newest picture, encodes, packetizes and sends it. A picture the
// encoder had no time for is replaced by the next one and counted as
// dropped: frames are never queued, so latency cannot grow. With
// `stream` false only the capture thread runs, feeding the picture tap.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>

#include <opencv2/core.hpp>

#include "shared/video/frame_source.hpp"
#include "shared/video/h264_codec.hpp"
#include "shared/video/rate_controller.hpp"
#include "shared/video/rtp_h264.hpp"

namespace inspect::video {

struct SenderSettings {
  bool enabled = true;
  /// false: capture only, for the picture tap (a head whose pictures are
  /// detected on the robot and not sent): no encoder, no socket, no RTCP; the
  /// network and encoder settings are not used.
  bool stream = true;
  /// Its threads are "<prefix>-capture", "-encode", "-rtcp" (top -H, bench_loop); at most 7 characters.
  std::string thread_prefix = "video";
  SourceSettings source;    // its width/height/fps are the stream's
  EncoderSettings encoder;  // width/height/fps are taken from `source`
  std::string host = "127.0.0.1";  // destination (the server), numeric or a name
  uint16_t port = 5600;
  std::size_t mtu = 1200;   // bytes per datagram including IP/UDP headers; [256, 9000]
  uint32_t ssrc = 0;        // 0 = random
  /// RTCP on the same socket (RFC 5761 rtcp-mux): sender reports to the
  /// destination every second; NACKs answered with RFC 4588 RTX packets from
  /// the history, PLIs with a keyframe, receiver reports into the stats.
  bool retransmission = true;
  std::size_t history_packets = 1024;  // packets kept for retransmission; [0, 65536]
  double history_s = 1.0;              // ...and for at most this long; [0.01, 10]
  /// Rate adaptation from the receiver reports (needs `retransmission`, the
  /// RTCP path); its start rate is encoder.bitrate_kbps, its ceiling
  /// max_kbps (0 = encoder.bitrate_kbps; the range always holds that rate).
  RateSettings adapt{.max_kbps = 0};
};

/// Checks the settings (ranges, encoder settings); "" or the first problem.
std::string validate(const SenderSettings& s);

struct SenderStats {
  bool enabled = false;
  uint32_t ssrc = 0;
  int width = 0, height = 0;
  double fps = 0;
  int bitrate_kbps = 0;
  std::string encoder;      // in use ("" before the first frame)
  std::string source;
  uint16_t port = 0;
  uint64_t captured = 0, encoded = 0, dropped = 0, keyframes = 0;
  uint64_t packets = 0, bytes = 0, send_errors = 0;
  uint64_t keyframe_requests = 0;
  // RTCP (rtcp-mux, docs/video.md "RTCP"):
  uint32_t rtx_ssrc = 0;
  uint64_t sender_reports = 0;       // SRs sent
  uint64_t receiver_reports = 0;     // report blocks about this stream received
  uint64_t nacks = 0;                // NACK packets received
  uint64_t nacked_packets = 0;       // sequence numbers asked for
  uint64_t retransmitted = 0;        // RTX packets sent
  uint64_t not_in_history = 0;       // asked for but no longer held
  uint64_t repeat_nacks = 0;         // asked again within a few ms (the receiver's second copy): not resent
  uint64_t plis = 0;                 // picture loss indications received
  uint64_t rtcp_errors = 0;          // datagrams on the socket that were not RTCP we accept
  double peer_loss_pct = -1;         // the receiver's last reported fraction lost; < 0 = no report yet
  double rtt_ms = -1;                // from the last report's LSR/DLSR; < 0 = none yet
  double encode_ms = 0;     // mean over the last second
  std::string error;        // last error, "" = none
  // Rate adaptation (RateController): what the encoder does now.
  bool adapt = false;
  int min_kbps = 0, max_kbps = 0;
  int rate_kbps = 0;        // bitrate in force
  int send_width = 0, send_height = 0;
  double send_fps = 0;      // frame rate in force (the source's, halved at level 1 and 2)
  int rate_level = 0;
  std::string rate_reason;  // why the rate or level last changed
  uint64_t rate_changed_us = 0;  // when (monotonic clock)
  uint64_t rate_changes = 0;
  uint64_t rate_skipped = 0;     // captured frames left out at a reduced frame rate
};

/// A change of settings from the operator; unset fields stay.
struct SenderChange {
  std::optional<bool> enabled;
  std::optional<int> width, height;
  std::optional<double> fps;
  std::optional<int> bitrate_kbps;
};

class VideoSender {
 public:
  /// Throws VideoError when the settings are invalid or the destination
  /// cannot be resolved. Nothing runs until start().
  explicit VideoSender(SenderSettings s);
  ~VideoSender();
  VideoSender(const VideoSender&) = delete;
  VideoSender& operator=(const VideoSender&) = delete;

  void start();
  void stop();  // joins the threads; idempotent

  /// Validates and applies a change at the next frame; "" or why it was refused.
  std::string apply(const SenderChange& c);
  /// The next encoded frame is an IDR with SPS/PPS.
  void requestKeyframe();
  /// Called on the capture thread with every captured picture (BGR) and its
  /// capture time, before it goes to the encoder; it must be quick (copy what
  /// it needs). Set before start().
  using PictureTap = std::function<void(const cv::Mat& bgr, uint64_t capture_us)>;
  void setPictureTap(PictureTap tap) { tap_ = std::move(tap); }
  SenderStats stats() const;
  uint32_t ssrc() const { return ssrc_; }

 private:
  void captureLoop();
  void encodeLoop();
  /// Opens the encoder for settings generation `gen`, or changes its bitrate
  /// in place; reopens it (with an IDR) when the size or rate changed.
  void prepareEncoder(std::unique_ptr<H264Encoder>& enc, uint64_t& enc_generation, uint64_t gen,
                      const EncoderSettings& es);
  /// What sending one encoded frame did.
  struct SentFigures {
    uint64_t packets = 0, bytes = 0, send_errors = 0;
    std::string error;  // the last send error ("" = none)
  };
  /// Packetizes a frame, sends its packets and keeps them for retransmission.
  void sendFrame(H264Packetizer& packetizer, const EncodedFrame& out, uint64_t capture_us,
                 std::vector<std::vector<uint8_t>>& packets, SentFigures& f);
  void feedbackLoop();
  void onFeedback(std::span<const uint8_t> datagram);
  void sendSenderReport();
  void setError(const std::string& e);

  mutable std::mutex mu_;
  std::condition_variable frame_cv_;  // encode thread waits for a picture
  std::condition_variable wake_cv_;   // capture thread waits for its next frame time, a change or stop
  SenderSettings s_;          // guarded by mu_
  uint64_t generation_ = 0;   // bumps on a change of size/fps/bitrate; guarded by mu_
  // Mailbox: the newest captured picture.
  cv::Mat slot_;
  uint64_t slot_capture_us_ = 0;
  uint32_t slot_index_ = 0;
  uint64_t slot_generation_ = 0;
  bool slot_full_ = false;
  SenderStats st_;            // guarded by mu_
  RateController rate_;       // guarded by mu_
  std::atomic<bool> keyframe_requested_{false};
  std::atomic<bool> running_{false};
  uint32_t ssrc_;
  uint32_t rtx_ssrc_;
  std::thread capture_thread_, encode_thread_, feedback_thread_;
  PictureTap tap_;
  struct Net;
  std::unique_ptr<Net> net_;
};

}  // namespace inspect::video
