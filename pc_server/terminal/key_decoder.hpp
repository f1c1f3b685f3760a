#pragma once
// Turns raw terminal bytes into teleop keys: w/a/s/d, arrow escape sequences
// (ESC [ A..D and ESC O A..D), space, q and a lone Esc. Holds no terminal.
#include <string>
#include <vector>

#include "pc_server/terminal/keyboard_teleop.hpp"

namespace inspect::server {

class KeyDecoder {
 public:
  using Key = KeyboardTeleop::Key;

  /// Decodes `bytes`; an unfinished escape sequence waits for more bytes or flush().
  std::vector<Key> feed(const std::string& bytes);
  /// Ends a pending escape sequence (no more bytes came): a lone ESC is kLeave.
  std::vector<Key> flush();
  /// True while an escape sequence is incomplete.
  bool pending() const { return !esc_.empty(); }

 private:
  std::string esc_;
};

}  // namespace inspect::server
