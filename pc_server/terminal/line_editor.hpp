#pragma once
// The console's input line on a raw terminal (docs/console.md "Keys"): typing
// and editing at the cursor, the history, and Tab completion from the command
// table (Console::completions). Pure: it is fed bytes and answers with the
// text to write; InteractiveConsole owns the terminal.
//
// Why our own and not a library: GNU readline is GPL-3 (pc_server is not), and
// libedit's readline emulation redraws the line itself, which fights the
// status line and the events printed above the prompt; what is needed here
// is about 200 lines (keys below), each tested in test_line_editor.cpp.
//
// Keys: printable bytes insert; Enter ends the line; Backspace, Delete,
// Ctrl-D (deletes, or ends the input on an empty line); Left/Right, Ctrl-B/F,
// Home/End, Ctrl-A/E; Ctrl-U/K kill to the start/end, Ctrl-W the word before;
// Up/Down, Ctrl-P/N the history; Tab completes the word at the cursor (one
// candidate: the word and a space; several: their common start, or the list
// when there is none to add); Ctrl-L redraws. Other control bytes and escape
// sequences are ignored.
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace inspect::server {

class LineEditor {
 public:
  /// The words that may replace the last word of `before_cursor` (which may be "").
  using Completer = std::function<std::vector<std::string>(const std::string& before_cursor)>;
  enum class Outcome { kEditing, kLine, kEof };

  LineEditor(std::string prompt, Completer completer, std::size_t max_line = 4096, std::size_t max_history = 500);

  /// Feeds one byte; kLine when it ended a line (takeLine), kEof on Ctrl-D
  /// on an empty line. What to write to the terminal accumulates in takeOutput.
  Outcome feed(char c);
  /// The line just ended (kLine); the editor is empty again.
  std::string takeLine();
  /// The text to write since the last call (echo, redraws, completion lists).
  std::string takeOutput();
  /// The prompt and the line with the cursor where it is, drawn from column 0
  /// (after background text was printed above).
  std::string render() const;

  const std::string& line() const { return buf_; }
  std::size_t cursor() const { return cur_; }
  const std::vector<std::string>& history() const { return history_; }

 private:
  void insert(const std::string& s);
  void erase(std::size_t from, std::size_t to);
  void moveTo(std::size_t pos);
  void complete();
  void recall(int step);
  void escape(char c);
  void redraw() { out_ += render(); }
  std::size_t prevChar(std::size_t pos) const;
  std::size_t nextChar(std::size_t pos) const;

  std::string prompt_;
  Completer completer_;
  std::size_t max_line_;
  std::size_t max_history_;
  std::string buf_;
  std::size_t cur_ = 0;
  std::string out_;
  std::string done_;
  std::string esc_;  // an escape sequence being read
  std::vector<std::string> history_;
  std::size_t hist_pos_ = 0;  // == history_.size(): the line being edited
  std::string draft_;         // the line being edited while the history is shown
};

}  // namespace inspect::server
