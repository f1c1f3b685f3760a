#pragma once
// People in the camera's pictures, on the robot (docs/human-awareness.md,
// "Detection on the robot"): a thread of its own beside the video encoder
// that takes the newest captured picture when a detection is due, runs the
// people detector (shared/perception) and turns each box into a bearing and,
// with the feet in view, a range on the floor (camera_geometry) at the PTZ
// angles of that moment. The capture thread only copies a picture when the
// detector is idle and due; the 100 Hz loop only reads the latest result
// under a short lock: neither ever waits for a detection.
//
// Pacing: at most `rate_hz`, and after a detection that took d seconds the
// next starts no sooner than d / max_core_share later, so the thread never
// takes more than that share of one core (a slower CPU lowers the rate).
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/core.hpp>

#include "shared/config/robot_config.hpp"
#include "shared/perception/camera_geometry.hpp"
#include "shared/perception/people_detector.hpp"

namespace inspect::client {

struct WatcherSettings {
  perception::PeopleDetectorOptions detector;
  int width = 640, height = 480;  // detection size (pictures of another size are resized)
  double rate_hz = 5.0;
  double max_core_share = 0.5;
  config::CameraMount mount;
  std::string thread_name = "people-detect";  // at most 15 characters
};

/// One person in one picture.
struct SeenPerson {
  perception::Sighting at;
  perception::PersonBox box;  // in the detected picture's pixels
};

/// The people of the latest detected picture.
struct PeopleView {
  uint64_t capture_us = 0;  // monotonic clock of the picture
  uint64_t seq = 0;         // detections so far (this one included)
  int width = 0, height = 0;
  double pan_rad = 0, tilt_rad = 0;
  std::vector<SeenPerson> people;
};

struct WatcherStats {
  uint64_t detections = 0;
  uint64_t offered = 0, taken = 0;  // pictures the capture thread offered / copied
  double rate_hz = 0;               // over the last detections (up to 10)
  double detect_ms = 0;             // mean wall time per detection (the same ones)
  std::string detector;
  std::string error;                // "" = none
};

class PeopleWatcher {
 public:
  /// Throws std::invalid_argument / std::runtime_error from the detector's
  /// options (a cascade file missing names it). Nothing runs until start().
  explicit PeopleWatcher(WatcherSettings s);
  ~PeopleWatcher();
  PeopleWatcher(const PeopleWatcher&) = delete;
  PeopleWatcher& operator=(const PeopleWatcher&) = delete;

  void start();
  void stop();  // joins; idempotent

  /// A captured BGR picture (the video sender's capture thread). Copied only
  /// when a detection is due and the thread is idle; cheap otherwise.
  void offer(const cv::Mat& bgr, uint64_t capture_us);
  /// The PTZ set-point now (the loop's thread); pictures taken from now on are
  /// read at these angles.
  void setPtz(double pan_rad, double tilt_rad);

  /// The latest detection, if any.
  std::optional<PeopleView> latest() const;
  /// Its sequence number (0 = none yet), without a lock or a copy: the loop
  /// asks this every tick and copies the view only when it is new.
  uint64_t latestSeq() const { return latest_seq_.load(); }
  WatcherStats stats() const;

 private:
  void loop();

  const WatcherSettings s_;
  perception::PeopleDetector detector_;
  std::atomic<double> pan_{0.0}, tilt_{0.0};
  std::atomic<int64_t> due_us_{0};     // the next detection may start from this monotonic time
  std::atomic<bool> busy_{false};      // a picture is waiting or being detected
  std::atomic<uint64_t> latest_seq_{0};
  mutable std::mutex mu_;
  std::condition_variable cv_;
  bool running_ = false;               // guarded by mu_
  cv::Mat pending_;                    // guarded by mu_
  uint64_t pending_us_ = 0;
  double pending_pan_ = 0, pending_tilt_ = 0;
  std::optional<PeopleView> latest_;   // guarded by mu_
  WatcherStats st_;                    // guarded by mu_
  std::vector<double> recent_ms_, recent_at_s_;  // guarded by mu_: the last detections
  std::thread thread_;
};

}  // namespace inspect::client
