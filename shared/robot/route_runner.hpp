#pragma once
// A route the robot drives by itself (Command.go_to: goto, route, inspect;
// docs/navigation.md, docs/gas.md): its goals one after the other through the
// navigator (go-to-goal, obstacle avoidance, boundary following), a dwell
// and a camera preset at inspection points, the hold or the retreat after a
// gas HIGH alarm, and the stall limit.
#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "inspect_robot/v1/link.pb.h"
#include "shared/config/robot_config.hpp"
#include "shared/navigation/navigator.hpp"
#include "shared/robot/core_event.hpp"
#include "shared/robot/safety_params.hpp"

namespace inspect::robot {

class RouteRunner {
 public:
  /// Most goals one go_to command may carry.
  static constexpr int kMaxGoals = 100;
  /// Cruise speed of a go_to command that gives none (clamped to the robot's limit).
  static constexpr double kDefaultSpeed_m_s = 0.5;

  /// A checked go_to command, ready to begin.
  struct Plan {
    std::unique_ptr<navigation::Navigator> navigator;
    double speed_m_s = 0.0;
  };
  /// Command path, allocates: checks `g` against the robot's limits and
  /// builds its navigator. Returns "" with `out` filled, or why not.
  static std::string plan(const v1::GoTo& g, const config::RobotConfig& robot, Plan& out);
  /// Begins a planned route at `pose` (the previous run must have been
  /// ended); returns its description ("inspection 'x': 5 goals at 0.40 m/s").
  std::string begin(Plan plan, const v1::GoTo& g, uint64_t command_id, const control::Pose2& pose);
  bool active() const { return navigator_ != nullptr; }
  /// The navigator of the current route; null when none.
  const navigation::Navigator* navigator() const { return navigator_.get(); }
  /// The operator, a safety stop or another run took over. The goals and
  /// the distance stay for telemetry.
  void end();

  /// What the core knows of the people around (null echoes: no awareness).
  struct People {
    const std::array<bool, 4>* person_echoes = nullptr;  // per sonar: its echo is a person
    double speed_factor = 1.0;                           // Eq 9
  };
  struct Step {
    control::Twist twist;
    std::optional<RunEnd> end;  // the route completed, failed, was given up
  };
  /// Tick: one navigation step from `pose` with the sonar ranges of the last
  /// frame; dt_s <= 0 (a command-time refresh) repeats the last twist.
  Step step(const control::Pose2& pose, const std::array<uint16_t, 4>& ultrasonic_mm, const People& people,
            double nav_stall_s, double dt_s, EventLog& events);

  /// A gas HIGH alarm (`why`: "<channel> HIGH alarm") while on the route.
  void onGasHigh(const std::string& why, GasReaction reaction, EventLog& events);
  /// `resume` while holding after a gas alarm: the route goes on. False if not holding.
  bool releaseGasHold(EventLog& events);

  /// nav_mode, dwell, waypoint label, goal distance/index/count, switches;
  /// `navigating`: the core is in NAVIGATING.
  void fillTelemetry(v1::Telemetry& t, bool navigating) const;
  /// Camera set-points of inspection points reached since the last take.
  std::vector<v1::Ptz>& ptz() { return ptz_out_; }

 private:
  struct GoalInfo {
    double dwell_s = 0.0;
    bool has_ptz = false;
    v1::Ptz ptz;
    std::string label;
  };
  /// Goal `i` was reached: dwell, camera preset (into ptz()).
  void arriveAt(std::size_t i, EventLog& events);
  /// Turns the route round: back through the goals already reached to the start.
  void startRetreat(const std::string& why, EventLog& events);

  std::unique_ptr<navigation::Navigator> navigator_;
  std::vector<navigation::Vec2> goals_;
  std::vector<GoalInfo> goal_info_;   // per goal of goals_
  std::size_t goal_index_ = 0;
  uint64_t command_id_ = 0;
  uint32_t switches_done_ = 0;        // automaton switches of the goals already reached
  double goal_distance_m_ = 0.0;
  double stall_clock_s_ = 0.0;        // time allowed to move (dt x Eq 9 factor) since the command
  double best_m_ = std::numeric_limits<double>::infinity();  // closest to the current goal so far
  double best_clock_s_ = 0.0;
  control::Twist twist_;              // the last tick's twist (after Eq 9)
  navigation::Vec2 start_;            // where the route began (retreat target)
  double dwell_left_s_ = 0.0;         // > 0: dwelling at the goal just reached
  std::string dwell_label_;           // its label
  bool final_dwell_ = false;          // dwelling at the last point: the route completes after it
  bool gas_hold_ = false;             // stopped and holding after a gas HIGH alarm
  bool retreating_ = false;           // going back after a gas HIGH alarm
  std::string retreat_reason_;
  std::vector<v1::Ptz> ptz_out_;
};

}  // namespace inspect::robot
