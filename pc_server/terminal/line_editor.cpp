#include "pc_server/terminal/line_editor.hpp"

#include <algorithm>
#include <utility>

namespace inspect::server {

namespace {
constexpr char ctrl(char c) { return static_cast<char>(c & 0x1f); }
bool continuationByte(char c) { return (static_cast<unsigned char>(c) & 0xc0) == 0x80; }
constexpr char kBell = '\a';

std::string commonStart(const std::vector<std::string>& words) {
  std::string s = words.front();
  for (const auto& w : words) {
    std::size_t n = 0;
    while (n < s.size() && n < w.size() && s[n] == w[n]) ++n;
    s.resize(n);
  }
  return s;
}
}  // namespace

LineEditor::LineEditor(std::string prompt, Completer completer, std::size_t max_line, std::size_t max_history)
    : prompt_(std::move(prompt)), completer_(std::move(completer)), max_line_(max_line), max_history_(max_history) {}

std::size_t LineEditor::prevChar(std::size_t pos) const {
  if (pos == 0) return 0;
  --pos;
  while (pos > 0 && continuationByte(buf_[pos])) --pos;
  return pos;
}

std::size_t LineEditor::nextChar(std::size_t pos) const {
  if (pos >= buf_.size()) return buf_.size();
  ++pos;
  while (pos < buf_.size() && continuationByte(buf_[pos])) ++pos;
  return pos;
}

std::string LineEditor::render() const {
  std::string s = "\r\x1b[K" + prompt_ + buf_;
  const auto left = std::count_if(buf_.begin() + static_cast<std::ptrdiff_t>(cur_), buf_.end(),
                                  [](char c) { return !continuationByte(c); });
  if (left > 0) s += "\x1b[" + std::to_string(left) + "D";
  return s;
}

void LineEditor::insert(const std::string& s) {
  if (buf_.size() + s.size() > max_line_) {
    out_ += kBell;
    return;
  }
  const bool at_end = cur_ == buf_.size();
  buf_.insert(cur_, s);
  cur_ += s.size();
  if (at_end) out_ += s;  // typing at the end: the echo is enough
  else redraw();
}

void LineEditor::erase(std::size_t from, std::size_t to) {
  if (from >= to) return;
  buf_.erase(from, to - from);
  cur_ = from;
  redraw();
}

void LineEditor::moveTo(std::size_t pos) {
  if (pos == cur_) return;
  cur_ = pos;
  redraw();
}

void LineEditor::recall(int step) {
  if (step < 0 && hist_pos_ == 0) return;
  if (step > 0 && hist_pos_ >= history_.size()) return;
  if (hist_pos_ == history_.size()) draft_ = buf_;
  hist_pos_ = static_cast<std::size_t>(static_cast<long>(hist_pos_) + step);
  buf_ = hist_pos_ == history_.size() ? draft_ : history_[hist_pos_];
  cur_ = buf_.size();
  redraw();
}

void LineEditor::complete() {
  if (!completer_) return;
  const std::string before = buf_.substr(0, cur_);
  const std::string partial = before.substr(before.find_last_of(" \t") + 1);  // npos + 1 = 0: the whole line
  const auto candidates = completer_(before);
  if (candidates.empty()) {
    out_ += kBell;
    return;
  }
  if (candidates.size() == 1) {
    const std::string& w = candidates.front();
    // "evals=" takes its value next to it; any other word is followed by a space.
    const bool open = !w.empty() && w.back() == '=';
    const bool spaced = cur_ < buf_.size() && buf_[cur_] == ' ';
    insert(w.substr(std::min(partial.size(), w.size())) + (open || spaced ? "" : " "));
    return;
  }
  const std::string common = commonStart(candidates);
  if (common.size() > partial.size()) {
    insert(common.substr(partial.size()));
    return;
  }
  std::string list;
  for (const auto& c : candidates) list += (list.empty() ? "" : "  ") + c;
  out_ += "\r\x1b[K" + list + "\n";
  redraw();
}

void LineEditor::escape(char c) {
  esc_.push_back(c);
  if (esc_.size() == 2) {
    if (c != '[' && c != 'O') esc_.clear();  // ESC and another key: both ignored
    return;
  }
  if (!(c >= 0x40 && c <= 0x7e)) {  // parameters of ESC [ ...
    if (esc_.size() > 16) esc_.clear();
    return;
  }
  const std::string seq = esc_.substr(1);
  esc_.clear();
  if (seq == "[A" || seq == "OA") recall(-1);
  else if (seq == "[B" || seq == "OB") recall(+1);
  else if (seq == "[C" || seq == "OC") moveTo(nextChar(cur_));
  else if (seq == "[D" || seq == "OD") moveTo(prevChar(cur_));
  else if (seq == "[H" || seq == "OH" || seq == "[1~" || seq == "[7~") moveTo(0);
  else if (seq == "[F" || seq == "OF" || seq == "[4~" || seq == "[8~") moveTo(buf_.size());
  else if (seq == "[3~") erase(cur_, nextChar(cur_));
}

LineEditor::Outcome LineEditor::feed(char c) {
  if (!esc_.empty()) {
    escape(c);
    return Outcome::kEditing;
  }
  switch (c) {
    case '\r':
    case '\n': {
      done_ = buf_;
      if (!buf_.empty() && (history_.empty() || history_.back() != buf_)) {
        history_.push_back(buf_);
        if (history_.size() > max_history_) history_.erase(history_.begin());
      }
      hist_pos_ = history_.size();
      draft_.clear();
      buf_.clear();
      cur_ = 0;
      out_ += "\n";
      return Outcome::kLine;
    }
    case '\x1b': esc_.push_back(c); break;
    case '\t': complete(); break;
    case '\x7f':
    case ctrl('H'): erase(prevChar(cur_), cur_); break;
    case ctrl('D'):
      if (buf_.empty()) return Outcome::kEof;
      erase(cur_, nextChar(cur_));
      break;
    case ctrl('A'): moveTo(0); break;
    case ctrl('E'): moveTo(buf_.size()); break;
    case ctrl('B'): moveTo(prevChar(cur_)); break;
    case ctrl('F'): moveTo(nextChar(cur_)); break;
    case ctrl('U'): erase(0, cur_); break;
    case ctrl('K'):
      buf_.resize(cur_);
      redraw();
      break;
    case ctrl('W'): {
      std::size_t from = cur_;
      while (from > 0 && buf_[from - 1] == ' ') --from;
      while (from > 0 && buf_[from - 1] != ' ') --from;
      erase(from, cur_);
      break;
    }
    case ctrl('P'): recall(-1); break;
    case ctrl('N'): recall(+1); break;
    case ctrl('L'): redraw(); break;
    default:
      if (static_cast<unsigned char>(c) >= 0x20) insert(std::string(1, c));  // printable or UTF-8
      break;
  }
  return Outcome::kEditing;
}

std::string LineEditor::takeLine() { return std::exchange(done_, std::string()); }

std::string LineEditor::takeOutput() { return std::exchange(out_, std::string()); }

}  // namespace inspect::server
