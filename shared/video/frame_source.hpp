#pragma once
// Where the robot's video frames come from: a V4L2 camera through OpenCV, a
// video file, the simulator's camera (mcu_sim --camera, through a frame slot),
// or a synthetic scene (the default when there is no camera).
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

#include "shared/video/video_error.hpp"

namespace inspect::video {

struct SourceSettings {
  /// "synthetic", "v4l2:/dev/videoN" (or just "/dev/videoN"), "file:PATH"
  /// (or any other path ending in a video extension), "sim:PATH" (the frame
  /// slot that `mcu_sim --camera PATH` writes, frame_slot.hpp).
  std::string uri = "synthetic";
  int width = 640;
  int height = 480;
  double fps = 30.0;
  /// V4L2 pixel format asked of the camera: "MJPG", "YUYV" or "" (driver's).
  std::string pixel_format;
  bool loop_file = true;  // a file source starts again at its end
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  /// Fills `bgr` (CV_8UC3, exactly width x height of the settings: resized if
  /// the device gives another size) with the next picture. `capture_us` is
  /// the time of capture on CLOCK_MONOTONIC (monoNowUs) and `frame_index`
  /// the source's frame counter; sources that draw (synthetic) put both into
  /// the picture. A camera blocks until its next frame; the synthetic source
  /// and files return at once (the caller paces them). Returns false at the
  /// end of a non-looping file or when the device fails (error() says why).
  virtual bool read(cv::Mat& bgr, uint64_t capture_us, uint32_t frame_index) = 0;
  virtual std::string describe() const = 0;
  virtual std::string error() const { return {}; }
  /// True when read() blocks on real time (a camera): the caller need not pace.
  virtual bool paced() const { return false; }
};

/// Opens the source named by `s.uri`. Throws VideoError naming the device or
/// file and what failed (not found, cannot open, no frames, not a frame slot).
///
/// `sim:PATH` gives the newest picture of the simulator's camera (resized to
/// the settings' size when the simulator renders another one), at most at the
/// settings' frame rate; it is paced by the simulator. When no new picture
/// comes for `kSimStallTimeoutMs` (or the simulator closes the slot), read()
/// returns false and error() says so; the caller reopens it later.
std::unique_ptr<FrameSource> openFrameSource(const SourceSettings& s);

/// How long a `sim:` source waits for the simulator's next picture before it
/// reports the simulator as stopped (also at least 3 of its frame periods).
inline constexpr int kSimStallTimeoutMs = 1000;

/// The synthetic scene alone (used by benchmarks and tests): a moving
/// pattern (a bouncing disc and a sweeping bar over a gradient, so the encoder
/// has motion to code), a large frame counter and the capture time in text,
/// and the machine-readable time code (timecode.hpp) along the top.
class SyntheticSource : public FrameSource {
 public:
  SyntheticSource(int width, int height);
  bool read(cv::Mat& bgr, uint64_t capture_us, uint32_t frame_index) override;
  std::string describe() const override;

 private:
  int width_, height_;
  cv::Mat background_;
};

}  // namespace inspect::video
