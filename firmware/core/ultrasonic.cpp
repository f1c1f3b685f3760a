#include "firmware/core/ultrasonic.hpp"

#include <algorithm>

namespace inspect::firmware {

namespace {
constexpr float kSoundMmPerUs = 0.343f;  // 343 m/s
}

uint16_t UltrasonicScheduler::toMm(const EchoCapture& c) const {
  if (!c.fell) return serial::kNoEcho;  // still high at the slot's end: nothing within it
  const float mm = static_cast<float>(c.width_us) * kSoundMmPerUs / 2.0f;
  if (mm > s_.ultrasonic_max_range_m * 1000.0f) return serial::kNoEcho;
  return static_cast<uint16_t>(std::max(mm, s_.ultrasonic_min_range_m * 1000.0f) + 0.5f);
}

int UltrasonicScheduler::tick(uint32_t now_ms, const EchoCapture& capture) {
  if (started_ && now_ms - slot_start_ms_ < s_.ultrasonic_slot_ms) return -1;
  if (started_ && current_ >= 0) {
    const auto i = static_cast<std::size_t>(current_);
    ++readings_[i];
    if (capture.rose) {
      missed_[i] = 0;
      ranges_[i] = toMm(capture);
    } else {
      if (missed_[i] < 255) ++missed_[i];
      ranges_[i] = serial::kNoEcho;
    }
  }
  started_ = true;
  slot_start_ms_ = now_ms;
  current_ = (current_ + 1) % serial::kUltrasonicCount;
  return current_;
}

bool UltrasonicScheduler::fault() const {
  return std::any_of(missed_.begin(), missed_.end(), [&](uint8_t m) { return m >= s_.ultrasonic_missed_limit; });
}

void ObstacleStop::update(uint16_t front_left_mm, uint16_t front_right_mm) {
  if (s_.obstacle_stop_m <= 0) {
    active_ = false;
    return;
  }
  const float nearest_m = static_cast<float>(std::min(front_left_mm, front_right_mm)) / 1000.0f;  // 0xFFFF: 65 m
  if (!active_ && nearest_m < s_.obstacle_stop_m) active_ = true;
  else if (active_ && nearest_m > s_.obstacle_clear_m) active_ = false;
}

void ObstacleStop::limit(float& left, float& right) const {
  if (!active_) return;
  const float common = (left + right) / 2.0f, half_difference = (right - left) / 2.0f;
  if (common <= 0.0f) return;  // backing away or turning on the spot: allowed
  left = -half_difference;
  right = half_difference;
}

}  // namespace inspect::firmware
