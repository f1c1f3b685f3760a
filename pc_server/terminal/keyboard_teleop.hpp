#pragma once
// Keyboard teleop as a pure state machine: keys and time in, velocity set-point
// out (docs/console.md, "Keyboard teleop").
// step: keys step the set-point, which stays until changed.
// hold: a key drives at a fixed speed while its auto-repeats keep arriving (deadman).
#include <string>

#include "pc_server/console/teleop_mode.hpp"

namespace inspect::server {

class KeyboardTeleop {
 public:
  using Mode = TeleopMode;  // the console's `teleop step|hold`
  enum class Key { kForward, kBack, kLeft, kRight, kZero, kLeave, kOther };

  struct Params {
    double step_v_m_s = 0.05;
    double step_w_rad_s = 0.1;
    double max_v_m_s = 1.0;
    double max_w_rad_s = 2.0;
    double hold_v_m_s = 0.3;             // hold mode: speed while w/s is held
    double hold_w_rad_s = 1.0;           // hold mode: yaw rate while a/d is held
    // Operator silence stops the robot within 300 ms of the last key (a
    // terminal whose auto-repeat delay is longer pauses once as a hold starts).
    double first_repeat_timeout_s = 0.3;
    double repeat_timeout_s = 0.2;       // several missed repeats at >= 10 Hz
  };

  explicit KeyboardTeleop(Mode mode) : KeyboardTeleop(mode, Params{}) {}
  KeyboardTeleop(Mode mode, const Params& params) : mode_(mode), p_(params) {}

  /// Applies a key pressed at `t_s`; true when the set-point changed.
  bool onKey(Key key, double t_s);
  /// Runs the hold-mode deadman at `t_s`; true when the set-point changed (to zero).
  bool tick(double t_s);
  /// Zeroes the set-point (e.g. the robot disconnected).
  void zero();

  double v() const { return v_steps_ * p_.step_v_m_s; }
  double w() const { return w_steps_ * p_.step_w_rad_s; }
  bool finished() const { return finished_; }
  Mode mode() const { return mode_; }
  /// E.g. "v [     |===  ] +0.15 m/s  w [     |     ] +0.00 rad/s".
  std::string gauge() const;

 private:
  bool set(int v_steps, int w_steps);
  int maxVSteps() const;
  int maxWSteps() const;

  Mode mode_;
  Params p_;
  // The set-point in whole steps, so that stepping back lands exactly on zero.
  int v_steps_ = 0;
  int w_steps_ = 0;
  bool finished_ = false;
  // hold mode
  Key held_ = Key::kOther;
  double last_key_s_ = 0;
  bool repeat_seen_ = false;
};

}  // namespace inspect::server
