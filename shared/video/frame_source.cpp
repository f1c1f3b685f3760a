#include "shared/video/frame_source.hpp"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <thread>

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "shared/video/frame_slot.hpp"
#include "shared/video/timecode.hpp"

namespace inspect::video {

namespace {

// Position on a back-and-forth sweep over [0, span] after `t` steps.
int bounce(int64_t t, int span) {
  if (span <= 0) return 0;
  const int64_t p = t % (2 * static_cast<int64_t>(span));
  return static_cast<int>(p <= span ? p : 2 * span - p);
}

std::string sizeText(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

bool startsWith(const std::string& s, const std::string& prefix) { return s.rfind(prefix, 0) == 0; }

bool hasVideoExtension(const std::string& path) {
  static const std::array<const char*, 12> kExt = {".mp4", ".mkv", ".avi", ".mov", ".m4v", ".webm",
                                                   ".ts",  ".h264", ".264", ".mjpeg", ".mjpg", ".flv"};
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return std::find(kExt.begin(), kExt.end(), ext) != kExt.end();
}

// A cv::VideoCapture (camera or file) giving BGR pictures of the asked size.
class CaptureSource : public FrameSource {
 public:
  bool read(cv::Mat& bgr, uint64_t, uint32_t) override {
    cv::Mat frame;
    if (!pending_.empty()) {
      frame = pending_;
      pending_.release();
    } else if (!grab(frame)) {
      return false;
    }
    toBgr(frame, bgr);
    return true;
  }
  std::string describe() const override { return describe_; }
  std::string error() const override { return error_; }

 protected:
  CaptureSource(std::string name, int width, int height) : name_(std::move(name)), width_(width), height_(height) {}

  // Reads the first picture (kept for the first read()) or throws.
  void firstFrame() {
    if (!cap_.read(pending_) || pending_.empty()) throw VideoError(name_ + ": no frames");
    source_size_ = pending_.size();
  }
  // The next picture from the device or file; false (error_ set) when none.
  virtual bool grab(cv::Mat& frame) {
    if (cap_.read(frame) && !frame.empty()) return true;
    error_ = name_ + ": read failed";
    return false;
  }
  void toBgr(const cv::Mat& frame, cv::Mat& bgr) const {
    cv::Mat colour;
    if (frame.channels() == 1) {
      cv::cvtColor(frame, colour, cv::COLOR_GRAY2BGR);
    } else if (frame.channels() == 4) {
      cv::cvtColor(frame, colour, cv::COLOR_BGRA2BGR);
    } else {
      colour = frame;
    }
    if (colour.cols == width_ && colour.rows == height_) {
      colour.copyTo(bgr);
    } else {
      const bool shrink = colour.cols > width_ || colour.rows > height_;
      cv::resize(colour, bgr, cv::Size(width_, height_), 0, 0, shrink ? cv::INTER_AREA : cv::INTER_LINEAR);
    }
  }

  std::string name_;  // "camera /dev/video0", "file x.mp4"
  int width_, height_;
  cv::VideoCapture cap_;
  cv::Mat pending_;
  cv::Size source_size_;
  std::string describe_;
  std::string error_;
};

class CameraSource : public CaptureSource {
 public:
  CameraSource(const SourceSettings& s, const std::string& device)
      : CaptureSource("camera " + device, s.width, s.height) {
    if (::access(device.c_str(), R_OK | W_OK) != 0)
      throw VideoError(name_ + ": cannot open (" + std::strerror(errno) + ")");
    if (!s.pixel_format.empty() && s.pixel_format.size() != 4)
      throw VideoError(name_ + ": pixel_format '" + s.pixel_format + "' is not a four-character code");
    if (!cap_.open(device, cv::CAP_V4L2))
      throw VideoError(name_ + ": cannot open (not a V4L2 capture device, or busy)");
    if (!s.pixel_format.empty()) {
      const auto& f = s.pixel_format;
      cap_.set(cv::CAP_PROP_FOURCC, cv::VideoWriter::fourcc(f[0], f[1], f[2], f[3]));
    }
    cap_.set(cv::CAP_PROP_FRAME_WIDTH, s.width);
    cap_.set(cv::CAP_PROP_FRAME_HEIGHT, s.height);
    cap_.set(cv::CAP_PROP_FPS, s.fps);
    firstFrame();
    const int fourcc = static_cast<int>(cap_.get(cv::CAP_PROP_FOURCC));
    const char fcc[5] = {static_cast<char>(fourcc & 0xFF), static_cast<char>((fourcc >> 8) & 0xFF),
                         static_cast<char>((fourcc >> 16) & 0xFF), static_cast<char>((fourcc >> 24) & 0xFF), 0};
    char fps[32];
    std::snprintf(fps, sizeof fps, "%.1f", cap_.get(cv::CAP_PROP_FPS));
    describe_ = name_ + " (V4L2 " + fcc + " " + sizeText(source_size_.width, source_size_.height) + " at " + fps +
                " fps, out " + sizeText(width_, height_) + ")";
  }
  bool paced() const override { return true; }
};

class FileSource : public CaptureSource {
 public:
  FileSource(const SourceSettings& s, std::string path)
      : CaptureSource("file " + path, s.width, s.height), path_(std::move(path)), loop_(s.loop_file) {
    if (!std::filesystem::is_regular_file(path_)) throw VideoError(name_ + ": not found");
    if (!cap_.open(path_, cv::CAP_FFMPEG)) throw VideoError(name_ + ": cannot open (not a video FFmpeg reads)");
    firstFrame();
    describe_ = name_ + " (" + sizeText(source_size_.width, source_size_.height) + ", out " +
                sizeText(width_, height_) + (loop_ ? ", looping)" : ")");
  }

 protected:
  bool grab(cv::Mat& frame) override {
    if (cap_.read(frame) && !frame.empty()) return true;
    if (!loop_) {
      error_ = name_ + ": end of file";
      return false;
    }
    // Reopening works for every container, seeking does not (raw .h264).
    cap_.release();
    if (cap_.open(path_, cv::CAP_FFMPEG) && cap_.read(frame) && !frame.empty()) return true;
    error_ = name_ + ": cannot read again from the start";
    return false;
  }

 private:
  std::string path_;
  bool loop_;
};

// The simulator's camera: the newest picture of the frame slot that mcu_sim
// writes (--camera PATH), at most at the asked frame rate, resized to the
// asked size. Paced by the simulator: read() waits for its next picture.
class SimCameraSource : public FrameSource {
 public:
  SimCameraSource(const SourceSettings& s, const std::string& path)
      : name_("sim:" + path), width_(s.width), height_(s.height), fps_(s.fps) {
    if (path.empty()) throw VideoError("video source 'sim:': no path (sim:PATH, the file of mcu_sim --camera PATH)");
    try {
      reader_ = std::make_unique<FrameSlotReader>(path);
    } catch (const VideoError& e) {
      std::string why = e.what();
      if (why.rfind(path + ": ", 0) == 0) why = why.substr(path.size() + 2);
      if (why == "not found") why += " (is mcu_sim running with --camera " + path + "?)";
      throw VideoError(name_ + ": " + why);
    }
    char fps[32];
    std::snprintf(fps, sizeof fps, "%g", reader_->fps());
    describe_ = name_ + " (mcu_sim pid " + std::to_string(reader_->writerPid()) + ", " +
                sizeText(reader_->width(), reader_->height()) + " at " + fps + " fps, out " +
                sizeText(width_, height_) + ")";
    if (reader_->width() != width_ || reader_->height() != height_)
      staging_.create(reader_->height(), reader_->width(), CV_8UC3);
  }

  bool read(cv::Mat& bgr, uint64_t, uint32_t) override {
    using Clock = std::chrono::steady_clock;
    const double slot_period_s = reader_->fps() > 0 ? 1.0 / reader_->fps() : 0.0;
    const auto stall = std::chrono::milliseconds(
        std::max<long>(kSimStallTimeoutMs, std::lround(3000.0 * slot_period_s)));
    // Frames closer together than 0.7 of our period are skipped, so a
    // simulator rendering faster than we send is sampled at our rate, and one
    // rendering at our rate is never halved by its jitter.
    const auto min_gap = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(fps_ > 0 ? 0.7 / fps_ : 0.0));
    const bool direct = staging_.empty();
    if (direct) bgr.create(height_, width_, CV_8UC3);
    cv::Mat& dst = direct ? bgr : staging_;
    auto deadline = Clock::now() + stall;
    for (;;) {
      const auto now = Clock::now();
      if (have_last_ && now < last_return_ + min_gap) {
        std::this_thread::sleep_until(std::min(last_return_ + min_gap, deadline));
        continue;
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now);
      const auto f = reader_->readNewer(last_seq_, dst.data, dst.step, std::max(left, std::chrono::milliseconds(0)));
      if (!f) {
        if (reader_->closed()) {
          error_ = name_ + ": mcu_sim closed the camera (it stopped)";
        } else {
          char s[32];
          std::snprintf(s, sizeof s, "%.1f", std::chrono::duration<double>(stall).count());
          error_ = name_ + ": no new picture for " + s + " s (" +
                   (reader_->writerAlive() ? "mcu_sim pid " + std::to_string(reader_->writerPid()) +
                                                 " is running but not writing"
                                           : "mcu_sim pid " + std::to_string(reader_->writerPid()) + " has exited") +
                   ")";
        }
        return false;
      }
      last_seq_ = f->seq;
      last_return_ = Clock::now();
      have_last_ = true;
      break;
    }
    if (!direct) {
      const bool shrink = staging_.cols > width_ || staging_.rows > height_;
      cv::resize(staging_, bgr, cv::Size(width_, height_), 0, 0, shrink ? cv::INTER_AREA : cv::INTER_LINEAR);
    }
    return true;
  }
  std::string describe() const override { return describe_; }
  std::string error() const override { return error_; }
  bool paced() const override { return true; }

 private:
  std::string name_;
  int width_, height_;
  double fps_;
  std::unique_ptr<FrameSlotReader> reader_;
  cv::Mat staging_;  // the slot's size, when it differs from ours
  uint64_t last_seq_ = 0;
  std::chrono::steady_clock::time_point last_return_{};
  bool have_last_ = false;
  std::string describe_;
  std::string error_;
};

}  // namespace

SyntheticSource::SyntheticSource(int width, int height) : width_(width), height_(height) {
  if (width < 64 || height < 64) throw VideoError("synthetic source: size " + sizeText(width, height) + " below 64x64");
  // Background: a horizontal colour gradient darkening downwards.
  background_.create(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y) {
    auto* row = background_.ptr<cv::Vec3b>(y);
    const double shade = 1.0 - 0.5 * y / height;
    for (int x = 0; x < width; ++x) {
      const double u = static_cast<double>(x) / width;
      row[x] = cv::Vec3b(static_cast<uint8_t>(shade * (60 + 150 * u)), static_cast<uint8_t>(shade * 120),
                         static_cast<uint8_t>(shade * (210 - 150 * u)));
    }
  }
}

bool SyntheticSource::read(cv::Mat& bgr, uint64_t capture_us, uint32_t frame_index) {
  background_.copyTo(bgr);
  const int unit = std::max(1, std::min(width_, height_) / 48);  // scales the scene with the picture
  const int64_t t = frame_index;

  // A bar sweeping left to right, and a disc bouncing off the edges.
  const int bar_w = 3 * unit;
  const int bar_x = static_cast<int>((t * unit) % (width_ + bar_w)) - bar_w;
  cv::rectangle(bgr, cv::Rect(bar_x, 0, bar_w, height_), cv::Scalar(40, 200, 240), cv::FILLED);
  const int r = 5 * unit;
  const cv::Point centre(r + bounce(t * 3 * unit / 2, width_ - 2 * r), r + bounce(t * unit, height_ - 2 * r));
  cv::circle(bgr, centre, r, cv::Scalar(230, 90, 30), cv::FILLED, cv::LINE_8);

  // The frame counter, large, and the capture time below it.
  const double scale = unit / 4.0;
  const int text_y = height_ / 2;
  cv::putText(bgr, std::to_string(frame_index), cv::Point(2 * unit, text_y), cv::FONT_HERSHEY_SIMPLEX, scale,
              cv::Scalar(255, 255, 255), std::max(1, unit / 2), cv::LINE_8);
  char when[48];
  std::snprintf(when, sizeof when, "%.3f ms", static_cast<double>(capture_us) / 1000.0);
  cv::putText(bgr, when, cv::Point(2 * unit, text_y + 3 * unit), cv::FONT_HERSHEY_SIMPLEX, scale / 3,
              cv::Scalar(255, 255, 255), std::max(1, unit / 6), cv::LINE_8);

  drawTimecode(bgr, capture_us, frame_index);
  return true;
}

std::string SyntheticSource::describe() const { return "synthetic " + sizeText(width_, height_); }

std::unique_ptr<FrameSource> openFrameSource(const SourceSettings& s) {
  if (s.width <= 0 || s.height <= 0) throw VideoError("video source: size " + sizeText(s.width, s.height) + " is not positive");
  const std::string& uri = s.uri;
  if (uri == "synthetic") return std::make_unique<SyntheticSource>(s.width, s.height);
  if (startsWith(uri, "v4l2:")) return std::make_unique<CameraSource>(s, uri.substr(5));
  if (startsWith(uri, "/dev/video")) return std::make_unique<CameraSource>(s, uri);
  if (startsWith(uri, "file:")) return std::make_unique<FileSource>(s, uri.substr(5));
  if (startsWith(uri, "sim:")) return std::make_unique<SimCameraSource>(s, uri.substr(4));
  if (hasVideoExtension(uri)) return std::make_unique<FileSource>(s, uri);
  throw VideoError("video source '" + uri + "': unknown (synthetic, v4l2:/dev/videoN, /dev/videoN, file:PATH, sim:PATH)");
}

}  // namespace inspect::video
