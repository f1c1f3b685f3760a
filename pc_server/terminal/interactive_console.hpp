#pragma once
// The console on a terminal: a prompt with line editing, history and Tab
// completion (LineEditor), a live status line of the selected robot on the
// bottom row, robot events as they arrive above the line being typed, and
// keyboard teleop. From a pipe: lines as they come, no editing.
#include <chrono>
#include <string>

#include "pc_server/console/console.hpp"
#include "pc_server/terminal/line_editor.hpp"
#include "pc_server/terminal/line_reader.hpp"
#include "pc_server/operator/stop_flag.hpp"
#include "pc_server/terminal/terminal.hpp"

namespace inspect::server {

class InteractiveConsole {
 public:
  InteractiveConsole(Console& console, StopFlag& stop, double status_refresh_hz);
  /// Runs until quit, end of input (Ctrl-D) or the stop request; restores the terminal.
  void run();

 private:
  /// Keyboard teleop of `robot_id` until q/Esc, disconnect or stop (the Console's TeleopHandler).
  bool teleop(TeleopMode mode, const std::string& robot_id);
  /// Redraws the status line when its period is due (or `force`).
  void refreshStatus(bool force);
  std::string statusText() const;
  /// Prints background text (events) above the current input line, then redraws it.
  void printAbove(const std::string& text);
  /// One line from the terminal through the editor, or from a pipe as it comes:
  /// kData (a line), kEof, kStopped or kTimeout (nothing yet).
  LineReader::Result nextLine(std::string& line);

  Console& console_;
  StopFlag& stop_;
  Terminal term_;
  LineReader reader_;
  LineEditor editor_;
  std::string pending_;  // bytes read from the terminal, not yet fed to the editor
  std::chrono::steady_clock::duration status_period_;
  std::chrono::steady_clock::time_point next_status_{};
};

}  // namespace inspect::server
