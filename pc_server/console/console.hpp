#pragma once
// The operator console: a thin parser and formatter over the operator service.
// It parses a line against the command table, runs the command's handler and
// prints robot events, control notes and completed runs between commands. The
// commands themselves are families registered in console.cpp (session, motion,
// gas, tuning, runs, scripts: console/*_commands.hpp), each reaching the robots
// through this console's OperatorService. It holds no terminal and no socket:
// lines in, text out (tested on strings).
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
#include "pc_server/console/command_family.hpp"
#include "pc_server/console/console_clock.hpp"
#include "pc_server/operator/control_arbiter.hpp"
#include "pc_server/operator/operator_service.hpp"
#include "pc_server/console/teleop_mode.hpp"
#include "pc_server/link/robot_registry.hpp"
#include "pc_server/operator/stop_flag.hpp"

namespace inspect::server {

class VideoHub;
class Recorder;
class TuningCommands;
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
  ~Console();
  Console(const Console&) = delete;
  Console& operator=(const Console&) = delete;

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
  /// Enables `sparkplug` (the SCADA edge node's report; empty function: none).
  void setSparkplugReport(std::function<std::string()> report) { sparkplug_report_ = std::move(report); }
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
  std::string helpText(const std::string& command = "") const;
  /// The words that may complete the last word of `partial_line` (a command
  /// name, a keyword, a choice, a robot id), from the command table; sorted.
  std::vector<std::string> completions(const std::string& partial_line) const;
  /// What is wrong with the command table's forms, one line each ("" = nothing).
  std::string tableProblems() const;

 // --- For the command families (console/*_commands.hpp) -------------------
  /// The console's output.
  std::ostream& out() { return out_; }
  /// Prints "<cmd>: <message>", counts an error and returns false.
  bool fail(const std::string& cmd, const std::string& message);
  /// Counts an error printed otherwise (a rejection, a failed teleop).
  void countError() { ++tally_.errors; }
  /// Counts an `expect` that held or failed.
  void countExpect(bool passed) { ++(passed ? tally_.expects_passed : tally_.expects_failed); }
  /// The selected robot when it is connected; otherwise prints why (as `cmd`) and returns nullopt.
  std::optional<std::string> connectedRobot(const std::string& cmd);
  /// Whether this session may move `robot` (see setSession); prints why not.
  bool mayMove(const std::string& robot, const std::string& cmd);
  /// Sends `cmd` to the selected robot through the service, waits for its Ack and prints the answer.
  bool sendAndReport(const std::string& name, v1::Command cmd, bool runs = false);
  /// A service call's result, waited for when pending, printed. With `runs` (track, goto,
  /// route) the command's COMPLETED Ack is printed when it comes (background()).
  bool report(const Issued& issued, bool runs = false);
  /// A call's result: the one it had at once, or (after printing the control note) the one awaited.
  CallResult outcomeOf(const Issued& issued);
  /// Sleeps up to `seconds` while pumping; false if the server is stopping.
  bool sleepPumping(double seconds);
  /// Now on this console's clock, in seconds (for elapsed times).
  double nowS() { return static_cast<double>(clock_->nowNs()) * 1e-9; }
  /// The time `seconds` from now on this console's clock, in its nanoseconds.
  int64_t deadlineAfter(double seconds) { return clock_->nowNs() + std::llround(seconds * 1e9); }
  StopFlag& stopFlag() { return stop_; }
  /// Whether this is an interactive terminal (alarm style on).
  bool alarmStyle() const { return alarm_style_; }
  ControlArbiter* arbiter() { return control_; }
  const TeleopHandler& teleopHandler() const { return teleop_handler_; }
  const std::function<std::string()>& foxgloveReport() const { return foxglove_report_; }
  const std::function<std::string()>& sparkplugReport() const { return sparkplug_report_; }
  scene::SiteMaps* siteMaps() const { return site_maps_; }
  /// The robot this session's last accepted `drive` went to (operatorPresent renews its lease).
  void setDriveRobot(const std::string& robot) { drive_robot_ = robot; }
  void requestQuit() { quit_ = true; }

 private:
  /// The command of that name in the table, or null.
  const ConsoleCommand* findCommand(const std::string& name) const;
  /// The result of a pending call, pumping while it waits (timed out when the server stops).
  CallResult await(const PendingCall& pending);

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
  std::function<std::string()> sparkplug_report_;
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
  /// The command families, in help's order, and their commands (console.cpp).
  std::vector<std::unique_ptr<CommandFamily>> families_;
  TuningCommands* tuning_ = nullptr;  // one of families_ (setTuningPaths)
  std::vector<ConsoleCommand> table_;
};

}  // namespace inspect::server
