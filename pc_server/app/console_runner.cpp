#include "pc_server/app/console_runner.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iostream>

#include "pc_server/app/cli_options.hpp"
#include "pc_server/terminal/interactive_console.hpp"
#include "pc_server/terminal/line_reader.hpp"
#include "pc_server/console/text_util.hpp"

namespace inspect::server {

std::vector<std::string> readScriptFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw UsageError("--script: cannot open '" + path + "': " + std::strerror(errno));
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

ConsoleRunner::ConsoleRunner(Console& console, StopFlag& stop, double status_refresh_hz)
    : console_(console), stop_(stop), status_refresh_hz_(status_refresh_hz) {}

bool ConsoleRunner::runLine(const std::string& line, int line_no) {
  const std::string t = trim(line);
  if (t.empty() || t[0] == '#') return true;
  std::cout << "[" << line_no << "] " << t << "\n";
  return console_.execute(line, line_no);
}

bool ConsoleRunner::finish(const std::string& what, bool interrupted) {
  const auto& t = console_.tally();
  std::cout << what << (interrupted ? " interrupted" : " done") << ": " << t.commands << " commands, "
            << t.expects_passed << " expects passed, " << t.expects_failed << " failed, " << t.errors << " errors\n";
  std::cout.flush();
  return !interrupted && t.errors == 0 && t.expects_failed == 0;
}

bool ConsoleRunner::runScript(const std::vector<std::string>& lines, const std::string& name) {
  bool interrupted = false;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (stop_.requested()) {
      interrupted = true;
      break;
    }
    runLine(lines[i], static_cast<int>(i + 1));
    if (console_.quitRequested()) break;
  }
  if (stop_.requested()) interrupted = true;
  return finish("script " + name, interrupted);
}

bool ConsoleRunner::runStream(int fd) {
  LineReader reader(fd, stop_);
  int line_no = 0;
  bool interrupted = false;
  for (;;) {
    std::string line;
    const auto r = reader.nextLine(line, 50);
    if (r == LineReader::Result::kTimeout) {
      console_.pump();  // events keep printing while the writer is quiet
      continue;
    }
    if (r == LineReader::Result::kStopped) {
      interrupted = true;
      break;
    }
    if (r == LineReader::Result::kEof) break;
    runLine(line, ++line_no);
    if (console_.quitRequested()) break;
  }
  return finish("input", interrupted);
}

void ConsoleRunner::runInteractive() {
  InteractiveConsole ui(console_, stop_, status_refresh_hz_);
  ui.run();
}

}  // namespace inspect::server
