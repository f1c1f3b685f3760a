#pragma once
// Tracking controller settings (config/control.yaml) and their loader.
#include <memory>
#include <string>

#include "shared/config/config_node.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/control/trajectory_tracker.hpp"
#include "shared/fuzzy/fis.hpp"

namespace inspect::config {

struct ControlConfig {
  control::TrackerParams tracker;   // geometry fields are filled from the robot config
  std::string fis_path = "config/fuzzy/fuzzy_pid.fis";
  bool use_lookup = true;
};

/// Reads the control config; `base_dir` resolves a relative fis path.
ControlConfig loadControlConfig(const ConfigNode& root, const std::string& base_dir);
/// Reads the file (unknown keys are errors). A relative `fuzzy_pid.fis` is
/// resolved against the current directory first, then the file's directory's parent.
ControlConfig loadControlConfigFile(const std::string& path);
/// Copies geometry and limits of the robot into the tracker parameters.
void applyRobot(ControlConfig& c, const RobotConfig& robot);
/// The robot, its tracking controllers and their fuzzy system, as the
/// closed-loop runs need them (the experiments, the benchmarks, the tuner).
struct TrackingSetup {
  RobotConfig robot;
  ControlConfig control;  // applyRobot done
  fuzzy::Fis fis;         // control.fis_path read
};
/// Reads both files, applies the robot, reads the fis. Throws ConfigError or fuzzy::FisError.
TrackingSetup loadTrackingSetup(const std::string& robot_path, const std::string& control_path);

/// Loads the fuzzy-PID scheduler named by the config. Throws ConfigError.
std::shared_ptr<control::FuzzyGainScheduler> loadScheduler(const ControlConfig& c);

}  // namespace inspect::config
