#include "pc_server/terminal/terminal.hpp"

#include <sys/ioctl.h>
#include <unistd.h>

#include <cstdio>
#include <iostream>

namespace inspect::server {

Terminal::Terminal(int in_fd, int out_fd) : in_fd_(in_fd), out_fd_(out_fd) {
  tty_ = ::isatty(in_fd_) && ::isatty(out_fd_);
  if (tty_) querySize();
}

Terminal::~Terminal() {
  leaveRawMode();
  disableStatusLine();
}

void Terminal::writeOut(const std::string& s) {
  // Console text goes through std::cout; keep the order by flushing it first.
  std::cout.flush();
  std::size_t off = 0;
  while (off < s.size()) {
    const auto n = ::write(out_fd_, s.data() + off, s.size() - off);
    if (n <= 0) return;
    off += static_cast<std::size_t>(n);
  }
}

void Terminal::querySize() {
  winsize ws{};
  if (::ioctl(out_fd_, TIOCGWINSZ, &ws) == 0 && ws.ws_row >= 3 && ws.ws_col >= 10) {
    rows_ = ws.ws_row;
    cols_ = ws.ws_col;
  }
}

void Terminal::setScrollRegion() {
  // Make room for the status line, then confine scrolling to the rows above it.
  writeOut("\n\x1b" "7\x1b[1;" + std::to_string(rows_ - 1) + "r\x1b" "8\x1b[A");
}

void Terminal::enableStatusLine() {
  if (!tty_ || status_) return;
  status_ = true;
  querySize();
  setScrollRegion();
}

void Terminal::disableStatusLine() {
  if (!status_) return;
  status_ = false;
  // Clear the status line, reset the scroll region, and leave the cursor at the bottom.
  writeOut("\x1b" "7\x1b[" + std::to_string(rows_) + ";1H\x1b[2K\x1b[r\x1b" "8\n");
}

void Terminal::drawStatus(const std::string& text, bool alarm) {
  if (!status_) return;
  const int old_rows = rows_, old_cols = cols_;
  querySize();
  if (rows_ != old_rows || cols_ != old_cols) setScrollRegion();
  std::string line = text.size() > static_cast<std::size_t>(cols_ - 1) ? text.substr(0, cols_ - 1) : text;
  std::string s = "\x1b" "7\x1b[" + std::to_string(rows_) + ";1H\x1b[2K";
  s += alarm ? "\x1b[1;37;41m" : "\x1b[7m";
  s += line + "\x1b[0m\x1b" "8";
  writeOut(s);
}

void Terminal::enterRawMode() {
  if (!tty_ || raw_) return;
  termios t{};
  if (::tcgetattr(in_fd_, &t) != 0) return;
  saved_ = t;
  t.c_lflag &= ~static_cast<tcflag_t>(ICANON | ECHO | IEXTEN);
  t.c_cc[VMIN] = 1;
  t.c_cc[VTIME] = 0;
  if (::tcsetattr(in_fd_, TCSAFLUSH, &t) != 0) return;
  raw_ = true;
}

void Terminal::showCursor(bool show) {
  if (tty_) writeOut(show ? "\x1b[?25h" : "\x1b[?25l");
}

void Terminal::leaveRawMode() {
  if (!raw_) return;
  raw_ = false;
  if (saved_) ::tcsetattr(in_fd_, TCSAFLUSH, &*saved_);
  showCursor(true);
}

}  // namespace inspect::server
