#include "shared/navigation/navigation_params.hpp"

#include <cmath>
#include <string>

namespace inspect::navigation {

const char* toString(SwitchingStyle s) {
  switch (s) {
    case SwitchingStyle::kHard: return "hard";
    case SwitchingStyle::kBlend: return "blend";
  }
  return "?";
}

namespace {

std::string bad(const char* name, double v, const char* rule) {
  return std::string(name) + " = " + std::to_string(v) + ": " + rule;
}

}  // namespace

std::string checkParams(const NavigationParams& p) {
  struct Positive {
    const char* name;
    double value;
  };
  const Positive positives[] = {
      {"goal_epsilon_m", p.goal_epsilon_m},         {"heading_kp", p.heading_kp},
      {"speed_kp", p.speed_kp},                     {"v_max_m_s", p.v_max_m_s},
      {"w_max_rad_s", p.w_max_rad_s},               {"caution_distance_m", p.caution_distance_m},
      {"guard_distance_m", p.guard_distance_m},     {"follow_distance_m", p.follow_distance_m},
      {"safety_distance_m", p.safety_distance_m},   {"follow_speed_m_s", p.follow_speed_m_s},
      {"follow_caution_m", p.follow_caution_m},
      {"avoid_speed_m_s", p.avoid_speed_m_s},       {"perception_range_m", p.perception_range_m},
      {"clear_shot_half_width_m", p.clear_shot_half_width_m},
  };
  for (const auto& q : positives)
    if (!std::isfinite(q.value) || q.value <= 0.0) return bad(q.name, q.value, "must be finite and > 0");
  const Positive non_negatives[] = {
      {"goal_release_m", p.goal_release_m},       {"heading_ki", p.heading_ki},
      {"heading_kd", p.heading_kd},               {"distance_hysteresis_m", p.distance_hysteresis_m},
      {"follow_gain_1_m", p.follow_gain_1_m},     {"follow_correction_max", p.follow_correction_max},
      {"search_turn_rad", p.search_turn_rad},
      {"follow_front_sector_rad", p.follow_front_sector_rad},
      {"follow_lookahead_m", p.follow_lookahead_m},     {"progress_margin_m", p.progress_margin_m},
      {"blend_max_weight", p.blend_max_weight},   {"min_dwell_s", p.min_dwell_s},
      {"chatter_window_s", p.chatter_window_s},   {"memory_s", p.memory_s},
      {"recency_s", p.recency_s},
  };
  for (const auto& q : non_negatives)
    if (!std::isfinite(q.value) || q.value < 0.0) return bad(q.name, q.value, "must be finite and >= 0");
  if (!(p.safety_distance_m < p.guard_distance_m))
    return bad("safety_distance_m", p.safety_distance_m, "must be below guard_distance_m");
  if (!(p.guard_distance_m < p.caution_distance_m))
    return bad("guard_distance_m", p.guard_distance_m, "must be below caution_distance_m");
  if (!(p.follow_distance_m > p.safety_distance_m && p.follow_distance_m <= p.guard_distance_m))
    return bad("follow_distance_m", p.follow_distance_m, "must lie in (safety_distance_m, guard_distance_m]");
  if (!(p.follow_caution_m > p.follow_distance_m && p.follow_caution_m <= p.caution_distance_m))
    return bad("follow_caution_m", p.follow_caution_m, "must lie in (follow_distance_m, caution_distance_m]");
  if (!(p.blend_max_weight < 0.5)) return bad("blend_max_weight", p.blend_max_weight, "must be < 0.5");
  if (!(p.search_turn_rad < 1.5)) return bad("search_turn_rad", p.search_turn_rad, "must be < 1.5 rad");
  return {};
}

}  // namespace inspect::navigation
