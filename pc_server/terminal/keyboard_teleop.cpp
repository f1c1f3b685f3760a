#include "pc_server/terminal/keyboard_teleop.hpp"

#include <algorithm>
#include <cmath>

#include "pc_server/console/text_util.hpp"

namespace inspect::server {

namespace {
std::string bar(double value, double max) {
  constexpr int kHalf = 5;
  int n = static_cast<int>(std::lround(std::clamp(value / max, -1.0, 1.0) * kHalf));
  if (n == 0 && value != 0) n = value > 0 ? 1 : -1;  // any motion shows
  std::string s(2 * kHalf + 1, ' ');
  s[kHalf] = '|';
  for (int i = 1; i <= std::abs(n); ++i) s[static_cast<std::size_t>(kHalf + (n > 0 ? i : -i))] = '=';
  return "[" + s + "]";
}
}  // namespace

int KeyboardTeleop::maxVSteps() const { return static_cast<int>(std::floor(p_.max_v_m_s / p_.step_v_m_s + 1e-9)); }
int KeyboardTeleop::maxWSteps() const {
  return static_cast<int>(std::floor(p_.max_w_rad_s / p_.step_w_rad_s + 1e-9));
}

bool KeyboardTeleop::set(int v_steps, int w_steps) {
  v_steps = std::clamp(v_steps, -maxVSteps(), maxVSteps());
  w_steps = std::clamp(w_steps, -maxWSteps(), maxWSteps());
  const bool changed = v_steps != v_steps_ || w_steps != w_steps_;
  v_steps_ = v_steps;
  w_steps_ = w_steps;
  return changed;
}

void KeyboardTeleop::zero() {
  set(0, 0);
  held_ = Key::kOther;
  repeat_seen_ = false;
}

bool KeyboardTeleop::onKey(Key key, double t_s) {
  if (finished_) return false;
  if (key == Key::kLeave) {
    finished_ = true;
    held_ = Key::kOther;
    return set(0, 0);
  }
  if (key == Key::kZero) {
    held_ = Key::kOther;
    repeat_seen_ = false;
    return set(0, 0);
  }
  if (key == Key::kOther) return false;
  if (mode_ == Mode::kStep) {
    switch (key) {
      case Key::kForward: return set(v_steps_ + 1, w_steps_);
      case Key::kBack: return set(v_steps_ - 1, w_steps_);
      case Key::kLeft: return set(v_steps_, w_steps_ + 1);
      case Key::kRight: return set(v_steps_, w_steps_ - 1);
      default: return false;
    }
  }
  // Hold: the same key again soon after is an auto-repeat; from then on the
  // repeats come every ~30-50 ms, so a short gap already means "released".
  repeat_seen_ = key == held_ && t_s - last_key_s_ <= p_.first_repeat_timeout_s;
  held_ = key;
  last_key_s_ = t_s;
  const int hv = static_cast<int>(std::lround(p_.hold_v_m_s / p_.step_v_m_s));
  const int hw = static_cast<int>(std::lround(p_.hold_w_rad_s / p_.step_w_rad_s));
  switch (key) {
    case Key::kForward: return set(hv, 0);
    case Key::kBack: return set(-hv, 0);
    case Key::kLeft: return set(0, hw);
    case Key::kRight: return set(0, -hw);
    default: return false;
  }
}

bool KeyboardTeleop::tick(double t_s) {
  if (mode_ != Mode::kHold || held_ == Key::kOther) return false;
  const double timeout = repeat_seen_ ? p_.repeat_timeout_s : p_.first_repeat_timeout_s;
  if (t_s - last_key_s_ <= timeout) return false;
  held_ = Key::kOther;
  repeat_seen_ = false;
  return set(0, 0);
}

std::string KeyboardTeleop::gauge() const {
  return "v " + bar(v(), p_.max_v_m_s) + " " + fmtSigned(v()) + " m/s  w " + bar(w(), p_.max_w_rad_s) + " " +
         fmtSigned(w()) + " rad/s";
}

}  // namespace inspect::server
