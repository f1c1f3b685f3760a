#include "sim/mcu_sim/camera_feed.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>

#include "shared/util/clock.hpp"
#include "shared/util/thread_cpu.hpp"
#include "shared/video/frame_slot.hpp"

namespace inspect::sim {

namespace {

// Keep at most this many render times (an hour at 30 fps is 108 000).
constexpr std::size_t kMaxSamples = std::size_t{1} << 20;

}  // namespace

struct CameraFeed::Slot {
  Slot(const std::string& path, int width, int height, double fps) : writer(path, width, height, fps) {}
  video::FrameSlotWriter writer;
};

CameraFeed::CameraFeed(const World& world, const config::CameraMount& mount, CameraFeedOptions opt)
    : opt_(std::move(opt)),
      view_(world, mount, opt_.width, opt_.height),
      slot_(std::make_unique<Slot>(opt_.path, opt_.width, opt_.height, opt_.fps)) {
  snapshot_.robot = world.start;
  snapshot_.people.reserve(world.pedestrians.size());
  render_ms_.reserve(4096);
}

CameraFeed::~CameraFeed() { stop(); }

void CameraFeed::publish(const Simulation& sim) {
  const auto& crowd = sim.pedestrians();
  const auto pan_tilt = sim.cameraPanTilt();
  std::lock_guard lk(mu_);
  snapshot_.robot = sim.state().pose;
  snapshot_.pan_rad = opt_.follows_ptz ? pan_tilt[0] : 0.0;
  snapshot_.tilt_rad = opt_.follows_ptz ? pan_tilt[1] : 0.0;
  snapshot_.sim_time_s = sim.timeS();
  peopleInView(crowd, snapshot_.people);
}

CameraScene CameraFeed::snapshot() const {
  std::lock_guard lk(mu_);
  return snapshot_;
}

void CameraFeed::start() {
  std::lock_guard lk(mu_);
  if (running_ || thread_.joinable()) return;
  running_ = true;
  thread_ = std::thread([this] { loop(); });
}

void CameraFeed::stop() {
  {
    std::lock_guard lk(mu_);
    running_ = false;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void CameraFeed::loop() {
  using Clock = std::chrono::steady_clock;
  const auto period = steadyDuration(1.0 / opt_.fps);
  CameraScene scene;
  scene.people.reserve(snapshot_.people.capacity());
  cv::Mat frame(opt_.height, opt_.width, CV_8UC3);
  uint32_t index = 0;
  auto next = Clock::now();
  std::unique_lock lk(mu_);
  while (running_) {
    if (cv_.wait_until(lk, next, [this] { return !running_; })) break;
    scene.robot = snapshot_.robot;
    scene.pan_rad = snapshot_.pan_rad;
    scene.tilt_rad = snapshot_.tilt_rad;
    scene.sim_time_s = snapshot_.sim_time_s;
    scene.people.assign(snapshot_.people.begin(), snapshot_.people.end());
    lk.unlock();

    const auto t0 = Clock::now();
    const double cpu0 = util::threadCpuMs();
    const uint64_t capture_us = monoNowUs();
    view_.render(scene, capture_us, index, frame);
    slot_->writer.write(frame.data, frame.step, capture_us, index);
    ++index;
    const double cpu_ms = util::threadCpuMs() - cpu0;
    const auto t1 = Clock::now();

    next += period;
    bool late = false;
    if (t1 > next + period) {  // fell behind: start again from now, no burst
      next = t1;
      late = true;
    }
    lk.lock();
    if (render_ms_.size() < kMaxSamples)
      render_ms_.push_back(static_cast<float>(std::chrono::duration<double, std::milli>(t1 - t0).count()));
    cpu_ms_total_ += cpu_ms;
    ++frames_;
    if (late) ++late_;
  }
}

CameraFeedStats CameraFeed::stats() const {
  std::vector<float> v;
  CameraFeedStats s;
  {
    std::lock_guard lk(mu_);
    v = render_ms_;
    s.late = late_;
    s.frames = frames_;
    s.cpu_ms_mean = s.frames ? cpu_ms_total_ / static_cast<double>(s.frames) : 0.0;
  }
  if (!v.empty()) {
    std::sort(v.begin(), v.end());
    auto at = [&](double q) { return v[std::min(v.size() - 1, static_cast<std::size_t>(q * (v.size() - 1) + 0.5))]; };
    s.render_ms_p50 = at(0.5);
    s.render_ms_p99 = at(0.99);
    s.render_ms_max = v.back();
  }
  return s;
}

std::string CameraFeed::summary() const {
  const CameraFeedStats s = stats();
  char buf[384];
  std::snprintf(buf, sizeof buf,
                "%s %s %dx%d at %g fps: frames=%llu late=%llu render p50 %.2f ms p99 %.2f ms max %.2f ms, "
                "CPU %.2f ms/frame",
                opt_.follows_ptz ? "camera" : "wide camera", opt_.path.c_str(), opt_.width, opt_.height, opt_.fps, static_cast<unsigned long long>(s.frames),
                static_cast<unsigned long long>(s.late), s.render_ms_p50, s.render_ms_p99, s.render_ms_max,
                s.cpu_ms_mean);
  return buf;
}

}  // namespace inspect::sim
