#pragma once
// mcu_sim's cameras (--camera PATH, --wide-camera PATH): what one head on the
// robot sees, the PTZ head at its pan and tilt or the fixed wide one
// (sim/camera_view.hpp), rendered at its frame rate on a thread of its own and
// written into a frame slot (shared/video/frame_slot.hpp) that robot_client
// reads as its `sim:PATH` video source. The real-time runner leaves a
// snapshot of the truth (pose, PTZ set-point, pedestrians) after each
// catch-up, a copy under a mutex: the 100 Hz MCU loop never waits for a
// picture. The camera runs on the wall clock (a real camera's rate), whatever
// the simulation's --rate.
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "shared/config/robot_config.hpp"
#include "sim/camera_view.hpp"
#include "sim/simulation.hpp"

namespace inspect::sim {

struct CameraFeedOptions {
  std::string path;  // the frame slot's file (/dev/shm/... keeps it in memory)
  int width = 640;
  int height = 480;
  double fps = 30.0;
  bool follows_ptz = true;  // the PTZ head (pan and tilt set-points); false: a fixed head (the wide one)
};

/// Render times of the pictures so far.
struct CameraFeedStats {
  uint64_t frames = 0;
  uint64_t late = 0;           // frame times missed (the renderer fell a period behind)
  double render_ms_p50 = 0;    // wall time per picture (render + write)
  double render_ms_p99 = 0;
  double render_ms_max = 0;
  double cpu_ms_mean = 0;      // the camera thread's CPU time per picture
};

class CameraFeed {
 public:
  /// Makes the frame slot (throws video::VideoError naming the path) and the
  /// renderer; nothing runs until start().
  CameraFeed(const World& world, const config::CameraMount& mount, CameraFeedOptions opt);
  ~CameraFeed();  // stop(); the slot is closed and its file removed
  CameraFeed(const CameraFeed&) = delete;
  CameraFeed& operator=(const CameraFeed&) = delete;

  /// Takes the truth of `sim` for the next picture (call on the simulation's
  /// thread; no allocation once the people list has its size).
  void publish(const Simulation& sim);
  /// The truth the next picture will show (for tests).
  CameraScene snapshot() const;
  void start();
  void stop();  // joins the thread; idempotent
  CameraFeedStats stats() const;
  /// "camera PATH 640x480 at 30 fps: frames=... late=... render p50 ... ms ...".
  std::string summary() const;

 private:
  void loop();

  CameraFeedOptions opt_;
  CameraView view_;
  struct Slot;  // the frame slot writer (kept out of this header)
  std::unique_ptr<Slot> slot_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  CameraScene snapshot_;  // guarded by mu_
  bool running_ = false;  // guarded by mu_
  std::thread thread_;
  std::vector<float> render_ms_;  // guarded by mu_
  double cpu_ms_total_ = 0;       // guarded by mu_
  uint64_t frames_ = 0;           // guarded by mu_
  uint64_t late_ = 0;             // guarded by mu_
};

}  // namespace inspect::sim
