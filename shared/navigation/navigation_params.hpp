#pragma once
// Parameters of the navigation behaviours and of the hybrid automaton
// (docs/navigation.md has the table with units, defaults and ranges).
// All obstacle distances are measured from the robot's reference point, the
// axle midpoint (docs/conventions.md), to an obstacle point; the robot's body
// is a circle of 0.35 m around it, so a distance d leaves d - 0.35 m of gap.
#include <string>

namespace inspect::navigation {

/// How go-to-goal and obstacle avoidance are combined outside boundary following.
enum class SwitchingStyle {
  kHard,   // the chapter's hard switching: one behaviour at a time, chosen by guards
  kBlend,  // the chapter's blended action: go-to-goal mixed with avoid, weight smooth in the obstacle distance
};
const char* toString(SwitchingStyle s);

struct NavigationParams {
  // --- goal ---------------------------------------------------------------
  double goal_epsilon_m = 0.10;      // epsilon: AT_GOAL (stop) within this distance of the goal
  double goal_release_m = 0.15;      // AT_GOAL is left only beyond goal_epsilon_m + this (hysteresis)

  // --- go-to-goal (Eqs 5.13-5.19) -------------------------------------------
  double heading_kp = 2.0;           // 1/s: w = kp e_theta (+ ki, kd terms), Eq 5.15
  double heading_ki = 0.0;           // 1/s^2
  double heading_kd = 0.0;           // dimensionless (rad/s per rad/s of error rate)
  double speed_kp = 0.5;             // 1/s: v = speed_kp |x_g - x|, Eq 5.19 (P only)
  double v_max_m_s = 0.5;            // forward speed limit of every behaviour (never reverses)
  double w_max_rad_s = 1.5;          // yaw-rate limit

  // --- obstacles ------------------------------------------------------------
  double caution_distance_m = 1.4;   // d_o: points closer than this make the avoid vector (Eq 5.20)
  double guard_distance_m = 0.9;     // Delta: go-to-goal -> boundary following below this
  double follow_distance_m = 0.8;    // distance kept to the boundary while following it
  double safety_distance_m = 0.6;    // below this: AVOID (0.25 m of gap left)
  double distance_hysteresis_m = 0.08;  // AVOID is left only above safety + this
  double follow_speed_m_s = 0.3;     // speed along a boundary
  double avoid_speed_m_s = 0.15;     // speed in AVOID
  double follow_gain_1_m = 2.5;      // distance-keeping correction per metre of distance error
  double follow_correction_max = 1.0;  // bound on that correction (1 = up to 45 deg toward/away)
  double follow_caution_m = 1.1;     // following: only points closer than this shape the boundary direction
  double follow_lookahead_m = 0.3;   // a fitted wall is assumed to go on this far beyond its last point ahead
  double follow_front_sector_rad = 0.5;  // following: points on the follow side or within this of straight ahead
  double search_turn_rad = 0.3;      // boundary lost: heading offset toward the boundary's side
  double progress_margin_m = 0.2;    // progress (Eq 5.25): |x - x_g| < d_tau - margin
  double clear_shot_half_width_m = 0.6;  // half width of the corridor toward the goal that must be free

  // --- switching ------------------------------------------------------------
  SwitchingStyle style = SwitchingStyle::kHard;
  double blend_max_weight = 0.45;    // avoid weight at the guard distance (< 0.5 so the blend never stalls)
  double min_dwell_s = 0.3;          // a mode is kept at least this long (not for AVOID / AT_GOAL entry)
  double chatter_window_s = 0.5;     // a switch this soon after the previous one counts as rapid

  // --- perception -----------------------------------------------------------
  double memory_s = 2.0;             // sonar points older than this are forgotten
  double perception_range_m = 2.0;   // sonar ranges beyond this are not remembered
  double recency_s = 0.4;            // weight of a point decays as exp(-age / recency_s); 0 = no decay
};

/// Empty when the parameters are usable, otherwise one line naming the first bad one.
std::string checkParams(const NavigationParams& p);

}  // namespace inspect::navigation
