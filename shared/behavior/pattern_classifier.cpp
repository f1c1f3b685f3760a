#include "shared/behavior/pattern_classifier.hpp"

#include <cmath>
#include <numbers>

namespace inspect::behavior {

Pattern rawPattern(double rel_x, double rel_y, double vx, double vy, Pattern previous, const PatternParams& p) {
  const double speed = std::hypot(vx, vy);
  if (!std::isfinite(speed) || speed < p.min_speed_m_s || rel_x < p.behind_m) return Pattern::kNone;
  const double psi = std::abs(std::atan2(vy, vx)) * 180.0 / std::numbers::pi;  // 0 = same direction, 180 = opposite
  const double across = std::abs(90.0 - psi);                                   // 0 = straight across
  if (across <= 90.0 - p.crossing_deg) return Pattern::kCrossing;
  if (psi <= p.along_deg) return std::abs(rel_y) < p.confront_lateral_m ? Pattern::kLeading : Pattern::kNone;
  if (psi >= 180.0 - p.along_deg) {
    if (std::abs(rel_y) < p.confront_lateral_m) return Pattern::kConfronting;
    return std::abs(rel_y) < p.max_lateral_m ? Pattern::kEncountering : Pattern::kNone;
  }
  // Between the bands: keep what we had (hysteresis).
  return previous;
}

Pattern PatternClassifier::debounce(Pattern raw, double dt_s) {
  if (raw == current_) {
    candidate_ = current_;
    held_s_ = 0;
    return current_;
  }
  if (raw != candidate_) {
    candidate_ = raw;
    held_s_ = 0;
  }
  held_s_ += dt_s;
  if (held_s_ >= p_.dwell_s) {
    current_ = candidate_;
    held_s_ = 0;
    ++switches_;
  }
  return current_;
}

Pattern PatternClassifier::step(const control::Pose2& robot, double px, double py, double vx, double vy, double dt_s) {
  const double c = std::cos(robot.theta_rad), s = std::sin(robot.theta_rad);
  const double dx = px - robot.x_m, dy = py - robot.y_m;
  const double rx = c * dx + s * dy, ry = -s * dx + c * dy;
  const double rvx = c * vx + s * vy, rvy = -s * vx + c * vy;
  return debounce(rawPattern(rx, ry, rvx, rvy, current_, p_), dt_s);
}

Pattern PatternClassifier::stepNone(double dt_s) { return debounce(Pattern::kNone, dt_s); }

}  // namespace inspect::behavior
