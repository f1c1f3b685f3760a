#pragma once
// What the console's tuning commands (identify, tune, gains) keep between
// commands: the configs, the fuzzy system, the paper's, working and tuned
// gains, and the plant tuned for. Internal to pc_server/console.
#include <optional>
#include <string>

#include "pc_server/console/tuning_commands.hpp"
#include "shared/config/control_config.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/control/gain_set.hpp"
#include "shared/control/plant_model.hpp"
#include "shared/fuzzy/fis.hpp"

namespace inspect::server {

struct TuningState {
  config::RobotConfig robot;
  config::ControlConfig control;
  fuzzy::Fis fis;                  // the fuzzy system of control.fis_path (or imported)
  bool fis_imported = false;       // push it along with the gains
  control::GainSet paper;          // config/control.yaml's (the paper's) gains
  control::GainSet working;        // what `gains set` edits and `gains push` sends
  std::optional<control::GainSet> tuned;
  std::string tuned_session;       // session id of `tuned`
  control::PlantModel plant;       // what `tune` tunes for
  std::string plant_source = "nominal (config/robot.yaml)";
  std::string last_session_dir;
};

}  // namespace inspect::server
