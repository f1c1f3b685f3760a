#pragma once
// One Foxglove client's outgoing messages (docs/foxglove.md, "Back-pressure"):
// bounded, in three lanes sent in priority order - control (serverInfo,
// advertise, status, service responses; never dropped), data (telemetry,
// events, scene, grids; the oldest dropped past the budget) and video (a frame
// that does not fit is dropped and that subscription then skips to the next
// keyframe, so the client never gets a delta frame without its reference).
// Pure: no sockets, no clock; the session owns one per client.
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>

namespace inspect::server::foxglove {

/// A message ready for the socket: `head` then the shared `body` (the same
/// serialized payload goes to every subscriber; only the 13-byte header differs).
struct OutMessage {
  std::string head;
  std::shared_ptr<const std::string> body;  // may be null
  bool binary = false;
  uint32_t subscription = 0;  // message data: the client's subscription (0: control)
  std::size_t bytes() const { return head.size() + (body ? body->size() : 0); }
};

class SendQueue {
 public:
  enum class Lane { kControl, kData, kVideo };
  struct Limits {
    std::size_t control_bytes = 8u << 20;  // past this the client is too slow to serve: close it
    std::size_t data_bytes = 2u << 20;
    std::size_t video_bytes = 4u << 20;
  };
  struct Counters {
    uint64_t queued = 0;             // messages accepted
    uint64_t sent = 0;               // handed to the socket (pop)
    uint64_t dropped_data = 0;       // data messages dropped (oldest first) for lack of room
    uint64_t dropped_video = 0;      // video frames dropped for lack of room
    uint64_t skipped_video = 0;      // delta frames skipped while waiting for a keyframe
  };

  SendQueue() = default;
  explicit SendQueue(const Limits& limits) : limits_(limits) {}

  /// Queues a control message; false when the control lane is over its limit
  /// (the caller closes the connection: a client that reads nothing of its control replies is gone).
  bool pushControl(OutMessage m);
  /// Queues a data message; drops the oldest queued data first if it does not fit.
  void pushData(OutMessage m);
  /// Queues a video frame of subscription `stream`. A subscription starts
  /// waiting for a keyframe; a frame that does not fit is dropped and the
  /// subscription waits for the next keyframe (queued frames of that
  /// subscription are dropped too when a keyframe needs their room).
  void pushVideo(uint32_t stream, bool keyframe, OutMessage m);
  /// A subscription ended (unsubscribed, its channel gone): its queued
  /// messages are dropped (the client no longer knows its id) and its keyframe state forgotten.
  void forgetStream(uint32_t stream);

  /// The next message to write: control, then data, then video.
  std::optional<OutMessage> pop();
  bool empty() const { return control_.empty() && data_.empty() && video_.empty(); }
  std::size_t queuedBytes() const { return control_bytes_ + data_bytes_ + video_bytes_; }
  std::size_t queuedMessages() const { return control_.size() + data_.size() + video_.size(); }
  const Counters& counters() const { return counters_; }
  uint64_t dropped() const { return counters_.dropped_data + counters_.dropped_video + counters_.skipped_video; }

 private:
  struct VideoItem {
    uint32_t stream = 0;
    OutMessage m;
  };
  Limits limits_;
  Counters counters_;
  std::deque<OutMessage> control_, data_;
  std::deque<VideoItem> video_;
  std::size_t control_bytes_ = 0, data_bytes_ = 0, video_bytes_ = 0;
  std::map<uint32_t, bool> need_keyframe_;
};

}  // namespace inspect::server::foxglove
