#pragma once
// The console's commands of the tuning host (docs/tuning.md): identify,
// tune and gains (tuning_gains.cpp). The host's state (plant, working gains,
// last session) is one TuningState per console, made on first use from the
// robot and control configs.
#include <atomic>
#include <memory>
#include <optional>
#include <string>

#include "pc_server/console/command_family.hpp"
#include "shared/control/gain_set.hpp"

namespace inspect::tuning {
struct TuneSetup;
struct TuneResult;
struct Comparison;
class Tuner;
}  // namespace inspect::tuning

namespace inspect::server {

class Console;
struct TuningState;

class TuningCommands : public CommandFamily {
 public:
  explicit TuningCommands(Console& console) : c_(console) {}
  std::vector<ConsoleCommand> commands() override;
  /// Where the tuning host reads the robot and control configs and writes
  /// its sessions (defaults: config/robot.yaml, config/control.yaml, runs/tuning).
  void setPaths(std::string robot_config, std::string control_config, std::string dir);

 private:
  bool cmdIdentify(const CommandArgs& a);
  bool cmdTune(const CommandArgs& a);
  bool cmdGains(const CommandArgs& a);
  /// `gains show [robot]`: working, the robot's, the paper's and the tuned set side by side.
  bool gainsShow(const CommandArgs& a, TuningState& ts);
  /// `gains set name=value ... | paper | tuned | robot`: the working set, checked.
  bool gainsSet(const CommandArgs& a, TuningState& ts);
  /// `tune list`: the tuning sessions in the catalog, newest first.
  bool cmdTuneList();
  /// tune's key=value options for the command table: each key's type and range.
  static std::vector<ArgSpec> tuneOptionKeys();
  /// Sets from tune's key=value options (parsed by the command table) each
  /// part of `s`, the plant's description and the start gains; "" or why not.
  std::string applyTuneOptions(const CommandArgs& a, TuningState& ts, tuning::TuneSetup& s,
                               std::string& plant_source, std::string& start);
  /// Runs the optimiser from `start` with its progress line (Ctrl-C cancels); nullopt (printed why) on failure.
  std::optional<tuning::TuneResult> runTuner(tuning::Tuner& tuner, const control::GainSet& start);
  /// Writes the session's files under the tuning directory and books it in the
  /// catalog; the session's id, or nullopt (printed why).
  std::optional<std::string> saveTuneSession(const tuning::TuneSetup& setup, const tuning::TuneResult& result,
                                             const tuning::Comparison& cmp, const std::string& params,
                                             const std::string& robot);
  /// The tuning host's state, loaded on first use; prints why (as `cmd`) and returns null on failure.
  TuningState* tuning(const std::string& cmd);
  /// Sends gains to a robot, reports its Ack and books the push in the catalog.
  bool pushGains(const std::string& robot, const control::GainSet& g, const std::string& source,
                 const std::string& session);

  Console& c_;
  struct Tuning {
    std::shared_ptr<TuningState> state;  // made on the first tuning command
    std::atomic<bool> cancel{false};     // Ctrl-C during tune (StopFlag's interrupt target)
    std::string robot_config = "config/robot.yaml";
    std::string control_config = "config/control.yaml";
    std::string dir = "runs/tuning";
  } tune_;
};

}  // namespace inspect::server
