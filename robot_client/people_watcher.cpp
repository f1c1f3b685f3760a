#include "robot_client/people_watcher.hpp"

#include <pthread.h>

#include <algorithm>
#include <chrono>

#include <opencv2/imgproc.hpp>

#include "shared/util/clock.hpp"
#include "shared/util/log.hpp"

namespace inspect::client {

namespace {
constexpr std::size_t kRecent = 10;
}

PeopleWatcher::PeopleWatcher(WatcherSettings s) : s_(std::move(s)), detector_(s_.detector) {
  // One core at most (OpenCV would spread HOG over every core); robot_client
  // uses OpenCV for nothing else that runs in parallel.
  cv::setNumThreads(1);
  st_.detector = perception::describe(s_.detector);
}

PeopleWatcher::~PeopleWatcher() { stop(); }

void PeopleWatcher::start() {
  std::lock_guard lk(mu_);
  if (running_ || thread_.joinable()) return;
  running_ = true;
  thread_ = std::thread([this] {
    pthread_setname_np(pthread_self(), s_.thread_name.substr(0, 15).c_str());
    loop();
  });
}

void PeopleWatcher::stop() {
  {
    std::lock_guard lk(mu_);
    running_ = false;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void PeopleWatcher::setPtz(double pan_rad, double tilt_rad) {
  pan_.store(pan_rad);
  tilt_.store(tilt_rad);
}

void PeopleWatcher::offer(const cv::Mat& bgr, uint64_t capture_us) {
  {
    std::lock_guard lk(mu_);
    ++st_.offered;
  }
  if (busy_.load() || static_cast<int64_t>(capture_us) < due_us_.load() || bgr.empty()) return;
  std::lock_guard lk(mu_);
  if (!running_) return;
  if (bgr.cols == s_.width && bgr.rows == s_.height)
    bgr.copyTo(pending_);
  else
    cv::resize(bgr, pending_, cv::Size(s_.width, s_.height), 0, 0, cv::INTER_AREA);
  pending_us_ = capture_us;
  pending_pan_ = pan_.load();
  pending_tilt_ = tilt_.load();
  ++st_.taken;
  busy_.store(true);
  cv_.notify_one();
}

void PeopleWatcher::loop() {
  cv::Mat picture;
  std::unique_lock lk(mu_);
  while (true) {
    cv_.wait(lk, [this] { return !running_ || busy_.load(); });
    if (!running_) break;
    cv::swap(picture, pending_);
    PeopleView view;
    view.capture_us = pending_us_;
    view.pan_rad = pending_pan_;
    view.tilt_rad = pending_tilt_;
    lk.unlock();

    perception::CameraPose cam;  // where the picture was taken (the detector's floor band goes by it)
    cam.width = picture.cols;
    cam.height = picture.rows;
    cam.mount = s_.mount;
    cam.pan_rad = view.pan_rad;
    cam.tilt_rad = view.tilt_rad;
    const uint64_t t0 = monoNowUs();
    std::vector<perception::PersonBox> boxes;
    std::string error;
    try {
      boxes = detector_.detect(picture, &cam);
    } catch (const std::exception& e) {
      error = e.what();
    }
    const uint64_t t1 = monoNowUs();
    view.width = picture.cols;
    view.height = picture.rows;
    for (const auto& b : boxes) view.people.push_back({perception::sightingOf(b.box, cam), b});
    // Pace: the rate, and the core share (d / share from the start of this one).
    const double took_s = static_cast<double>(t1 - t0) / 1e6;
    const double gap_s = std::max(1.0 / s_.rate_hz, took_s / s_.max_core_share);
    due_us_.store(static_cast<int64_t>(t0) + static_cast<int64_t>(gap_s * 1e6));

    lk.lock();
    view.seq = ++st_.detections;
    if (!error.empty() && error != st_.error) log::warn("perception", "detector: ", error);
    st_.error = error;
    if (recent_ms_.size() == kRecent) {
      recent_ms_.erase(recent_ms_.begin());
      recent_at_s_.erase(recent_at_s_.begin());
    }
    recent_ms_.push_back(took_s * 1e3);
    recent_at_s_.push_back(static_cast<double>(t1) / 1e6);
    double sum = 0;
    for (const double m : recent_ms_) sum += m;
    st_.detect_ms = sum / static_cast<double>(recent_ms_.size());
    st_.rate_hz = recent_at_s_.size() >= 2
                      ? static_cast<double>(recent_at_s_.size() - 1) / (recent_at_s_.back() - recent_at_s_.front())
                      : 0.0;
    latest_ = std::move(view);
    latest_seq_.store(st_.detections);
    busy_.store(false);
  }
}

std::optional<PeopleView> PeopleWatcher::latest() const {
  std::lock_guard lk(mu_);
  return latest_;
}

WatcherStats PeopleWatcher::stats() const {
  std::lock_guard lk(mu_);
  WatcherStats s = st_;
  // A rate measured long ago is no rate now.
  if (!recent_at_s_.empty() && static_cast<double>(monoNowUs()) / 1e6 - recent_at_s_.back() > 3.0) s.rate_hz = 0;
  return s;
}

}  // namespace inspect::client
