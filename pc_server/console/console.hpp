#pragma once
// The operator console's commands: parsing, dispatch and output. It holds no
// terminal and no socket: lines in, text out (tested on strings); the robots
// are reached through the registry (state) and a CommandSink (commands).
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "pc_server/link/command_sink.hpp"
#include "pc_server/console/command_args.hpp"
#include "pc_server/console/console_clock.hpp"
#include "pc_server/operator/control_arbiter.hpp"
#include "pc_server/operator/operator_service.hpp"
#include "pc_server/console/teleop_mode.hpp"
#include "pc_server/link/robot_registry.hpp"
#include "pc_server/operator/stop_flag.hpp"
#include "shared/catalog/catalog.hpp"
#include "shared/control/gain_set.hpp"

namespace inspect::tuning {
struct TuneSetup;
struct TuneResult;
struct Comparison;
class Tuner;
}  // namespace inspect::tuning

namespace inspect::server {

class VideoHub;
class Recorder;
namespace scene {
class SiteMaps;
}

class Console {
 public:
  struct Options {
    double ack_timeout_s = 1.0;    // stop/estop/resume/drive wait this long for the Ack
    double poll_period_s = 0.02;   // expect ... within, wait
    double ack_pump_period_s = 0.05;  // waiting for a command's Ack: status and events printed this often
    double max_v_m_s = 1.0;        // drive limits (the keyboard gauge uses the same)
    double max_w_rad_s = 2.0;
    // A Foxglove client's session (pc_server/foxglove): its teleop is the
    // Teleop panel's (set-points that lapse), so `drive` (re-sent until stop)
    // is refused; and it does not vouch for the server's console thread (the
    // link's console watchdog listens to the consoles operators type in).
    bool allow_drive = true;
    bool feeds_watchdog = true;
    // > 0: `drive`'s set-point lapses this long after the operator's last
    // sign of presence (operatorPresent(): an attached console's every line
    // and keep-alive); 0: held until stop (the server's own console, whose
    // thread the console watchdog watches).
    double drive_lease_s = 0.0;
  };
  /// Runs keyboard teleop on the selected robot until the operator leaves; false on failure.
  using TeleopHandler = std::function<bool(TeleopMode mode, const std::string& robot_id)>;

  /// Counts of a session, for the script summary and the exit status.
  struct Tally {
    int commands = 0;
    int errors = 0;
    int expects_passed = 0;
    int expects_failed = 0;
  };

  Console(RobotRegistry& registry, CommandSink& sink, std::ostream& out, StopFlag& stop);
  Console(RobotRegistry& registry, CommandSink& sink, std::ostream& out, StopFlag& stop, Options options);

  /// Runs one line (blank lines and '#' comments are fine); false if it failed
  /// (an error, or an expect that did not hold). `line_no` appears in expect results.
  bool execute(const std::string& line, int line_no);

  /// Background work between commands: selects the first robot to connect when
  /// none is selected and returns the text of new robot events and of completed
  /// runs ("robot1: goto completed"). Call it often.
  std::string background();
  /// background() printed to the output, then the idle hook; used while waiting.
  void pump();
  /// The operator is there (a line or a keep-alive came): the lease of this
  /// session's `drive` set-point starts again, while it still holds the robot.
  void operatorPresent();
  /// The clock this console reads and waits on (default: the real one; tests
  /// pass one they advance themselves). Must outlive the console.
  void setClock(ConsoleClock& clock) { clock_ = &clock; }
  ConsoleClock& clock() { return *clock_; }
  /// Called while the console waits (e.g. to refresh the status line).
  void setIdleHook(std::function<void()> hook) { idle_hook_ = std::move(hook); }
  /// Interactive terminals: alarm lines in red with the terminal bell.
  void setAlarmStyle(bool on) { alarm_style_ = on; }
  /// Enables `teleop` (only an interactive terminal has one).
  void setTeleopHandler(TeleopHandler handler) { teleop_handler_ = std::move(handler); }

  /// Makes this console a session of `arbiter`: its motion commands need the
  /// robot's control (taken on first use when free), `control` shows and
  /// changes it, and notes from other sessions print in background().
  void setSession(ControlArbiter* arbiter, uint64_t session);
  uint64_t session() const { return session_; }
  /// Starts this console's event feed at the newest event: a session that
  /// attaches mid-run does not replay the registry's buffer (up to
  /// kMaxPendingEvents old events); `alarms` shows what is in force.
  void eventsFromNow() { event_cursor_ = registry_.eventCursor(); }

  /// `select <robot>` as a typed call (a Foxglove call names its robot so):
  /// prints "selected robot1" (or why not, as `select`); false when the id is not valid.
  bool select(const std::string& robot);

  bool quitRequested() const { return quit_; }
  const std::string& selected() const { return selected_; }
  const Tally& tally() const { return tally_; }
  const Options& options() const { return options_; }
  RobotRegistry& registry() { return registry_; }
  /// Enables snapshot and the video figures (null: the server has no video).
  void setVideo(VideoHub* hub) { video_ = hub; }
  VideoHub* video() const { return video_; }
  /// Enables `foxglove` (the bridge's report; empty function: no bridge).
  void setFoxgloveReport(std::function<std::string()> report) { foxglove_report_ = std::move(report); }
  /// Where `inspect` and `route` note the site map of the route they send (null: nowhere).
  void setSiteMaps(scene::SiteMaps* maps) {
    site_maps_ = maps;
    service_->setRunContext(recorder_, site_maps_);
  }
  /// Enables record/runs/run (null: the server records nothing).
  void setRecorder(Recorder* r) {
    recorder_ = r;
    catalog_notices_ = 0;
    service_->setRunContext(recorder_, site_maps_);
  }
  Recorder* recorder() const { return recorder_; }
  /// The robot's status line with the video figures and the recording mark ("| REC <run-id>").
  std::string statusText(const std::string& robot) const;
  CommandSink& sink() { return sink_; }
  /// The operator service this console's commands call (docs/console.md).
  OperatorService& service() { return *service_; }
  /// Where the tuning host reads the robot and control configs and writes
  /// its sessions (defaults: config/robot.yaml, config/control.yaml, runs/tuning).
  void setTuningPaths(std::string robot_config, std::string control_config, std::string dir);

  /// The text of `help` (all commands) or `help <command>`; empty for an unknown command.
  static std::string helpText(const std::string& command = "");
  /// The words that may complete the last word of `partial_line` (a command
  /// name, a keyword, a choice, a robot id), from the command table; sorted.
  std::vector<std::string> completions(const std::string& partial_line) const;
  /// What is wrong with the command table's forms, one line each ("" = nothing).
  static std::string tableProblems();

 private:
  using Handler = bool (Console::*)(const CommandArgs& a);
  /// A command: its forms of typed arguments (command_args.hpp: the syntax,
  /// the argument errors and completion come from them), its help, its handler.
  struct CommandDef {
    const char* name;
    std::vector<CommandForm> forms;
    const char* summary;
    const char* details;
    Handler run;
  };
  /// Every command, by family (help lists them in this order).
  static const std::vector<CommandDef>& commands();
  static std::vector<CommandDef> sessionCommands();
  static std::vector<CommandDef> motionCommands();
  static std::vector<CommandDef> gasCommands();
  static std::vector<CommandDef> tuningCommands();
  static std::vector<CommandDef> runCommands();
  static std::vector<CommandDef> scriptCommands();
  static const CommandDef* findCommand(const std::string& name);

  bool cmdHelp(const CommandArgs& a);
  bool cmdRobots(const CommandArgs& a);
  bool cmdSelect(const CommandArgs& a);
  bool cmdStatus(const CommandArgs& a);
  bool cmdDrive(const CommandArgs& a);
  bool cmdTeleop(const CommandArgs& a);
  bool cmdTrack(const CommandArgs& a);
  bool cmdGoto(const CommandArgs& a);
  bool cmdRoute(const CommandArgs& a);
  bool cmdStop(const CommandArgs& a);
  bool cmdEstop(const CommandArgs& a);
  bool cmdResume(const CommandArgs& a);
  bool cmdVideo(const CommandArgs& a);
  bool cmdPtz(const CommandArgs& a);
  bool cmdSnapshot(const CommandArgs& a);
  bool cmdFoxglove(const CommandArgs& a);
  bool cmdRecord(const CommandArgs& a);
  bool cmdRuns(const CommandArgs& a);
  bool cmdRun(const CommandArgs& a);
  bool cmdReport(const CommandArgs& a);
  bool cmdExport(const CommandArgs& a);
  bool cmdReplay(const CommandArgs& a);
  bool cmdInspect(const CommandArgs& a);
  bool cmdAlarms(const CommandArgs& a);
  bool cmdAck(const CommandArgs& a);
  bool cmdIdentify(const CommandArgs& a);
  bool cmdTune(const CommandArgs& a);
  bool cmdGains(const CommandArgs& a);
  struct TuningState;
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
  /// A run of the catalog and its directory; prints why not (as `cmd`) when there is none.
  std::optional<std::pair<catalog::RunDetail, std::string>> findRun(const std::string& cmd, const std::string& id);
  bool cmdWait(const CommandArgs& a);
  bool cmdExpect(const CommandArgs& a);
  bool cmdEcho(const CommandArgs& a);
  bool cmdQuit(const CommandArgs& a);

  /// Prints "<cmd>: <message>" and returns false.
  bool fail(const std::string& cmd, const std::string& message);
  /// The selected robot when it is connected; otherwise prints why (as `cmd`) and returns nullopt.
  std::optional<std::string> connectedRobot(const std::string& cmd);
  /// Whether this session may move `robot` (see setSession); prints why not.
  bool mayMove(const std::string& robot, const std::string& cmd);
  bool cmdControl(const CommandArgs& a);
  /// Sends `cmd` to the selected robot through the service, waits for its Ack and prints the answer.
  bool sendAndReport(const std::string& name, v1::Command cmd, bool runs = false);
  /// A service call's result, waited for when pending, printed. With `runs` (track, goto,
  /// route) the command's COMPLETED Ack is printed when it comes (background()).
  bool report(const Issued& issued, bool runs = false);
  /// The result of a pending call, pumping while it waits (timed out when the server stops).
  CallResult await(const PendingCall& pending);
  /// A call's result: the one it had at once, or (after printing the control note) the one awaited.
  CallResult outcomeOf(const Issued& issued);
  /// Sleeps up to `seconds` while pumping; false if the server is stopping.
  bool sleepPumping(double seconds);
  /// Now on this console's clock, in seconds (for elapsed times).
  double nowS() { return static_cast<double>(clock_->nowNs()) * 1e-9; }
  /// The time `seconds` from now on this console's clock, in its nanoseconds.
  int64_t deadlineAfter(double seconds) { return clock_->nowNs() + std::llround(seconds * 1e9); }

  RobotRegistry& registry_;
  CommandSink& sink_;
  std::ostream& out_;
  StopFlag& stop_;
  Options options_;
  SteadyConsoleClock steady_clock_{stop_};
  ConsoleClock* clock_ = &steady_clock_;
  std::function<void()> idle_hook_;
  TeleopHandler teleop_handler_;
  VideoHub* video_ = nullptr;
  std::string drive_robot_;  // the robot this session's last accepted `drive` went to
  Recorder* recorder_ = nullptr;
  uint64_t catalog_notices_ = 0;  // the recorder's catalog notices printed so far
  std::function<std::string()> foxglove_report_;
  scene::SiteMaps* site_maps_ = nullptr;
  bool alarm_style_ = false;
  std::string selected_;
  uint64_t event_cursor_ = 0;
  ControlArbiter* control_ = nullptr;
  std::optional<OperatorService> service_;
  uint64_t session_ = 0;  // this session's place in the registry's event feed (from the start for the first)
  bool quit_ = false;
  Tally tally_;
  /// An accepted long-running command waiting for its COMPLETED Ack (at most one per robot).
  struct Run {
    std::string robot_id;
    uint64_t command_id = 0;
    std::string name;
  };
  std::vector<Run> runs_;
  struct Tuning {  // the tuning host's state (console_tuning.cpp)
    std::shared_ptr<TuningState> state;  // made on the first tuning command
    std::atomic<bool> cancel{false};     // Ctrl-C during tune (StopFlag's interrupt target)
    std::string robot_config = "config/robot.yaml";
    std::string control_config = "config/control.yaml";
    std::string dir = "runs/tuning";
  } tune_;
};

}  // namespace inspect::server
