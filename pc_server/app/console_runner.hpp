#pragma once
// Drives a Console from a script, a pipe, or the interactive terminal (with the
// live status line and keyboard teleop).
#include <string>
#include <vector>

#include "pc_server/console/console.hpp"
#include "pc_server/operator/stop_flag.hpp"

namespace inspect::server {

class ConsoleRunner {
 public:
  ConsoleRunner(Console& console, StopFlag& stop, double status_refresh_hz);

  /// Runs `lines` (a script's text), echoing each command with its line number.
  /// True when every command succeeded and every expect held (and nothing interrupted it).
  bool runScript(const std::vector<std::string>& lines, const std::string& name);
  /// Reads commands from `fd` (a pipe or file) like a script until EOF, quit or stop.
  bool runStream(int fd);
  /// The interactive console on the terminal until quit, EOF (Ctrl-D) or stop.
  void runInteractive();

 private:
  bool runLine(const std::string& line, int line_no);
  bool finish(const std::string& what, bool interrupted);

  Console& console_;
  StopFlag& stop_;
  double status_refresh_hz_;
};

/// Reads a script file into lines; throws UsageError naming the file when it cannot.
std::vector<std::string> readScriptFile(const std::string& path);

}  // namespace inspect::server
