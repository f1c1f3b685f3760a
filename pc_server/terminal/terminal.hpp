#pragma once
// The operator's terminal: a bottom status line kept out of the scrolling
// output (ANSI scroll region) and a raw key mode for teleop. Everything is
// restored by the destructor, which also runs on SIGINT/SIGTERM shutdown.
#include <optional>
#include <string>

#include <termios.h>

namespace inspect::server {

class Terminal {
 public:
  /// `in_fd`/`out_fd`: normally 0 and 1.
  Terminal(int in_fd, int out_fd);
  ~Terminal();
  Terminal(const Terminal&) = delete;
  Terminal& operator=(const Terminal&) = delete;

  /// True when both ends are terminals.
  bool isTty() const { return tty_; }
  /// Reserves the bottom line for the status (no-op when not a tty).
  void enableStatusLine();
  /// Gives the bottom line back and resets the scroll region.
  void disableStatusLine();
  /// Redraws the status line (cursor position is kept). `alarm` draws it in red.
  void drawStatus(const std::string& text, bool alarm);
  /// Keys without Enter and without echo (Ctrl-C still raises SIGINT); the
  /// line editor and teleop read keys in it.
  void enterRawMode();
  /// Back to the mode before enterRawMode, with the cursor shown.
  void leaveRawMode();
  /// Hides the cursor (teleop's gauge) or shows it again.
  void showCursor(bool show);
  bool rawMode() const { return raw_; }

 private:
  void querySize();
  void setScrollRegion();
  void writeOut(const std::string& s);

  int in_fd_;
  int out_fd_;
  bool tty_ = false;
  bool status_ = false;
  bool raw_ = false;
  int rows_ = 24;
  int cols_ = 80;
  std::optional<termios> saved_;
};

}  // namespace inspect::server
