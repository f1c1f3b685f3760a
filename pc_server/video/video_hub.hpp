#pragma once
// The server's video side: the RTP receiver for every robot's streams (the
// PTZ head's and, when streamed, the wide head's: video_streams.hpp names
// them), keyframe requests back over the link, SDP files and RTP forwarding
// for standard players, snapshots (PNG) and the live window. Thread-safe.
// Calls taking a `stream` take its streamName(): the robot id for the PTZ head.
#include <atomic>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <boost/asio/ip/udp.hpp>

#include "inspect_robot/v1/link.pb.h"
#include "pc_server/link/command_sink.hpp"
#include "pc_server/video/video_config.hpp"
#include "shared/video/video_receiver.hpp"

namespace inspect::server {

class VideoHub {
 public:
  /// Binds the UDP port and creates the directory; throws util::StartupError naming
  /// what failed. `link_bind` is used when config.bind is empty.
  VideoHub(const VideoServerConfig& config, const std::string& link_bind, CommandSink& sink);
  ~VideoHub();
  VideoHub(const VideoHub&) = delete;
  VideoHub& operator=(const VideoHub&) = delete;

  uint16_t port() const;
  void start();
  void stop();

  /// Every telemetry envelope of a robot: learns its streams' SSRCs
  /// (video, wide_video) and the clock offset (from send_time_us), and accepts
  /// their RTP from `address` ("ip:port" of its link). `recv_us` is the
  /// server's receive time (monoNowUs).
  void onTelemetry(const std::string& robot_id, const std::string& address, const v1::Envelope& env,
                   uint64_t recv_us);

  std::optional<video::StreamStats> stats(const std::string& stream) const;
  video::ReceiverCounters counters() const;
  /// Writes the stream's latest decoded picture as PNG to `path` ("" = <dir>/<stem>_<n>.png).
  /// Returns the path written, or throws std::runtime_error saying why not.
  std::string snapshot(const std::string& stream, const std::string& path = "");
  /// <dir>/<stem>.sdp ("" before the stream was seen; robot1.sdp, robot1.wide.sdp).
  std::string sdpPath(const std::string& stream) const;
  /// The port the stream's RTP is forwarded to for players (0 = none).
  uint16_t forwardPort(const std::string& stream) const;
  bool windowShown() const { return window_running_; }
  /// Every intact access unit of every stream (for recording); set before start().
  void setAccessUnitHook(video::VideoReceiver::AccessUnitHook f) { receiver_->setAccessUnitHook(std::move(f)); }

 private:
  struct Stream {
    uint32_t ssrc = 0;
    std::string source_ip;
    int64_t offset_us = 0;
    uint16_t forward_port = 0;
    std::string sdp_path;
    bool sdp_has_params = false;
    int64_t last_snapshot_us = 0;
    int snapshot_count = 0;
  };
  void followStream(const std::string& name, uint32_t ssrc, const std::string& ip, int64_t offset);
  void writeSdp(const std::string& name, Stream& r, bool with_params);
  void onFrame(const std::string& stream, const cv::Mat& bgr, uint64_t capture_us);
  void forward(const std::string& stream, const std::vector<uint8_t>& datagram);
  void windowLoop();

  const VideoServerConfig config_;
  CommandSink& sink_;
  std::unique_ptr<video::VideoReceiver> receiver_;
  boost::asio::io_context fwd_io_;
  boost::asio::ip::udp::socket fwd_socket_;
  mutable std::mutex mu_;
  std::map<std::string, Stream> streams_;
  std::map<std::string, std::deque<int64_t>> offsets_;  // per robot: server - robot clock + one-way delay, recent
  uint16_t next_forward_port_;
  std::thread window_thread_;
  std::atomic<bool> window_running_{false};
  std::atomic<bool> stopping_{false};
};

}  // namespace inspect::server
