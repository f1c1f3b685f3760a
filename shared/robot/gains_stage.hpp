#pragma once
// Tracking gains pushed from the server (Command.gains, docs/tuning.md):
// checked and staged when the command arrives, put in force together at the
// next control tick, so that a tick never runs with half a gain set.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "inspect_robot/v1/link.pb.h"
#include "shared/config/control_config.hpp"
#include "shared/control/fuzzy_pid.hpp"
#include "shared/control/gain_set.hpp"
#include "shared/robot/core_event.hpp"

namespace inspect::robot {

class GainsStage {
 public:
  /// The control config's gains are version 0; `scheduler` may be null.
  GainsStage(const config::ControlConfig& control, std::shared_ptr<control::FuzzyGainScheduler> scheduler);

  /// Command path, may allocate and block: checks a GainsUpdate and stages
  /// it. A pushed fuzzy system is compiled here (its lookup surface: tens of
  /// ms), so it is refused while `moving` (the wheels depend on every tick).
  v1::Ack stage(const v1::Command& cmd, bool moving, v1::Mode mode);

  /// What applyPending() put in force: the GAINS_APPLIED event, and the new
  /// fuzzy system if the update brought one.
  struct Applied {
    CoreEvent event;
    std::shared_ptr<control::FuzzyGainScheduler> new_scheduler;
  };
  /// Tick: puts staged gains in force (nothing, and no allocation, when none
  /// are staged). `tracking`: a path is being tracked (the event says so).
  std::optional<Applied> applyPending(bool tracking);

  const control::GainSet& gains() const { return gains_; }
  uint32_t version() const { return version_; }
  const std::shared_ptr<control::FuzzyGainScheduler>& scheduler() const { return scheduler_; }
  const std::string& fisName() const { return fis_name_; }
  void setFisName(std::string name) { fis_name_ = std::move(name); }

 private:
  struct Pending {
    control::GainSet gains;
    uint32_t version = 0;
    std::shared_ptr<control::FuzzyGainScheduler> scheduler;  // null = keep the fuzzy system
    std::string fis_name;
    std::string source;
  };

  bool use_lookup_;
  control::GainSet gains_;
  uint32_t version_ = 0;
  std::shared_ptr<control::FuzzyGainScheduler> scheduler_;
  std::string fis_name_;
  std::optional<Pending> pending_;
};

}  // namespace inspect::robot
