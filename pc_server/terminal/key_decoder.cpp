#include "pc_server/terminal/key_decoder.hpp"

namespace inspect::server {

namespace {
using Key = KeyboardTeleop::Key;

Key plainKey(char c) {
  switch (c) {
    case 'w': case 'W': case 'k': return Key::kForward;
    case 's': case 'S': case 'j': return Key::kBack;
    case 'a': case 'A': case 'h': return Key::kLeft;
    case 'd': case 'D': case 'l': return Key::kRight;
    case ' ': case 'x': case 'X': case '0': return Key::kZero;
    case 'q': case 'Q': return Key::kLeave;
    default: return Key::kOther;
  }
}

Key arrowKey(char c) {
  switch (c) {
    case 'A': return Key::kForward;
    case 'B': return Key::kBack;
    case 'C': return Key::kRight;
    case 'D': return Key::kLeft;
    default: return Key::kOther;
  }
}
}  // namespace

std::vector<Key> KeyDecoder::feed(const std::string& bytes) {
  std::vector<Key> out;
  for (char c : bytes) {
    if (esc_.empty()) {
      if (c == '\x1b') esc_.push_back(c);
      else out.push_back(plainKey(c));
      continue;
    }
    if (esc_.size() == 1) {
      if (c == '[' || c == 'O') {
        esc_.push_back(c);
      } else {
        // ESC followed by something else: the ESC was a key of its own.
        out.push_back(Key::kLeave);
        esc_.clear();
        if (c == '\x1b') esc_.push_back(c);
        else out.push_back(plainKey(c));
      }
      continue;
    }
    // Inside ESC [ ... : parameters until a final byte in 0x40..0x7e.
    esc_.push_back(c);
    if (c >= 0x40 && c <= 0x7e) {
      out.push_back(esc_.size() == 3 ? arrowKey(c) : Key::kOther);
      esc_.clear();
    } else if (esc_.size() > 16) {
      out.push_back(Key::kOther);
      esc_.clear();
    }
  }
  return out;
}

std::vector<Key> KeyDecoder::flush() {
  std::vector<Key> out;
  if (esc_.size() == 1) out.push_back(Key::kLeave);
  else if (!esc_.empty()) out.push_back(Key::kOther);
  esc_.clear();
  return out;
}

}  // namespace inspect::server
