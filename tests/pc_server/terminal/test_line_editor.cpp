// The console's input line on a raw terminal: editing, history and Tab
// completion, fed byte by byte as the terminal sends them
// (pc_server/terminal/line_editor.hpp).
#include <gtest/gtest.h>

#include "pc_server/terminal/line_editor.hpp"

using namespace inspect::server;

namespace {

using Outcome = LineEditor::Outcome;

/// Feeds `keys`; the lines ended, in order (an Eof appears as "<eof>").
std::vector<std::string> type(LineEditor& e, const std::string& keys) {
  std::vector<std::string> lines;
  for (char c : keys) {
    const auto o = e.feed(c);
    if (o == Outcome::kLine) lines.push_back(e.takeLine());
    if (o == Outcome::kEof) lines.push_back("<eof>");
  }
  return lines;
}

std::vector<std::string> commandWords(const std::string& before) {
  // A small table: commands, then "tune" keys.
  const std::vector<std::string> commands{"drive", "status", "stop", "track", "try", "tune"};
  const auto space = before.find(' ');
  std::vector<std::string> pool = commands;
  std::string partial = before;
  if (space != std::string::npos) {
    if (before.compare(0, space, "tune") != 0) return {};
    pool = {"evals=", "ref=", "ref=circle", "ref=line", "seed=", "seeds="};
    partial = before.substr(before.find_last_of(' ') + 1);
    if (partial.find('=') == std::string::npos)
      pool = {"evals=", "ref=", "seed=", "seeds="};
    else
      pool = {"ref=circle", "ref=line"};
  }
  std::vector<std::string> out;
  for (const auto& w : pool)
    if (w.compare(0, partial.size(), partial) == 0) out.push_back(w);
  return out;
}

}  // namespace

TEST(LineEditor, TypingEchoesAndEnterEndsTheLine) {
  LineEditor e("> ", nullptr);
  EXPECT_EQ(type(e, "status"), std::vector<std::string>{});
  EXPECT_EQ(e.takeOutput(), "status");  // typed at the end: the echo alone
  EXPECT_EQ(type(e, "\r"), std::vector<std::string>{"status"});
  EXPECT_EQ(e.takeOutput(), "\n");
  EXPECT_EQ(e.line(), "");
  EXPECT_EQ(type(e, "a\nb\r"), (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(e.render(), "\r\x1b[K> ");
}

TEST(LineEditor, EditsAtTheCursor) {
  LineEditor e("> ", nullptr);
  type(e, "goto 2 3");
  type(e, "\x1b[D\x1b[D\x02");  // Left, Left, Ctrl-B: before "2 3"... at "2"
  EXPECT_EQ(e.cursor(), 5u);
  type(e, "1");
  EXPECT_EQ(e.line(), "goto 12 3");
  EXPECT_EQ(e.render(), "\r\x1b[K> goto 12 3\x1b[3D");
  type(e, "\x7f\x7f");  // Backspace twice: "goto 2 3", the space gone too
  EXPECT_EQ(e.line(), "goto2 3");
  type(e, "\x01\x1b[3~\x04");  // Home (Ctrl-A), Delete, Ctrl-D deletes at the cursor
  EXPECT_EQ(e.line(), "to2 3");
  type(e, "\x05\x17");  // End, Ctrl-W: the word before
  EXPECT_EQ(e.line(), "to2 ");
  type(e, "\x1b[H\x0b");  // Home, Ctrl-K: to the end
  EXPECT_EQ(e.line(), "");
  type(e, "abc\x1b[D\x15");  // Ctrl-U: to the start
  EXPECT_EQ(e.line(), "c");
  EXPECT_EQ(e.cursor(), 0u);
  type(e, "\x1bOF\x1b[1~\x1b[4~");  // End, Home, End in their other spellings
  EXPECT_EQ(e.cursor(), 1u);
}

TEST(LineEditor, CtrlDOnAnEmptyLineEndsTheInput) {
  LineEditor e("> ", nullptr);
  EXPECT_EQ(type(e, "x\x04"), std::vector<std::string>{});  // deletes nothing past the end
  EXPECT_EQ(type(e, "\x7f\x04"), std::vector<std::string>{"<eof>"});
}

TEST(LineEditor, HistoryRecallsAndKeepsTheDraft) {
  LineEditor e("> ", nullptr, 4096, 3);
  type(e, "one\rtwo\rtwo\r\rthree\rfour\r");
  // Repeats and empty lines are not kept; at most 3.
  EXPECT_EQ(e.history(), (std::vector<std::string>{"two", "three", "four"}));
  type(e, "dra");
  type(e, "\x1b[A");
  EXPECT_EQ(e.line(), "four");
  type(e, "\x10\x10\x10");  // Ctrl-P past the oldest stays there
  EXPECT_EQ(e.line(), "two");
  type(e, "\x1b[B\x0e\x1b[B\x1b[B");
  EXPECT_EQ(e.line(), "dra");  // back to the draft
  type(e, "\x1b[A!");
  EXPECT_EQ(type(e, "\r"), std::vector<std::string>{"four!"});
}

TEST(LineEditor, TabCompletesFromTheCompleter) {
  LineEditor e("> ", commandWords);
  type(e, "dr\t");
  EXPECT_EQ(e.line(), "drive ");  // one candidate: the word and a space
  type(e, "\x15tr\t");
  EXPECT_EQ(e.line(), "tr");  // track, try: no common start to add: the list
  EXPECT_EQ(e.takeOutput().find("\r\x1b[Ktrack  try\n\r\x1b[K> tr") != std::string::npos, true);
  type(e, "\x15st\t");
  EXPECT_EQ(e.line(), "st");
  type(e, "a\t");
  EXPECT_EQ(e.line(), "status ");
  type(e, "\x15tune s\t");
  EXPECT_EQ(e.line(), "tune seed");  // seed=, seeds=: their common start
  type(e, "=\t");
  EXPECT_EQ(e.takeOutput().back(), '\a');  // nothing to offer: the bell
  type(e, "\x15tune re\t");
  EXPECT_EQ(e.line(), "tune ref=");  // a key takes its value next to it
  type(e, "l\t");
  EXPECT_EQ(e.line(), "tune ref=line ");
  type(e, "\x15tu 3\x01\x06\x06\t");  // completing in the middle: no second space
  EXPECT_EQ(e.line(), "tune 3");
}

TEST(LineEditor, BoundsTheLineAndIgnoresOtherKeys) {
  LineEditor e("> ", nullptr, 5);
  type(e, "abcdefg");
  EXPECT_EQ(e.line(), "abcde");
  EXPECT_NE(e.takeOutput().find('\a'), std::string::npos);
  type(e, "\x15\x1b[1;5C\x1b[99Z\x1bx\x07\x12y");  // Ctrl-Right, unknown sequences, Alt-x, Ctrl-G, Ctrl-R
  EXPECT_EQ(e.line(), "y");
  type(e, "\x1b[12");  // an unfinished sequence swallows what follows up to its final byte
  type(e, "zw");
  EXPECT_EQ(e.line(), "yw");
}

TEST(LineEditor, MovesOverUtf8CharactersWhole) {
  LineEditor e("> ", nullptr);
  type(e, "echo h\xc3\xa9");  // "é" is two bytes
  EXPECT_EQ(e.render(), "\r\x1b[K> echo h\xc3\xa9");
  type(e, "\x1b[D");
  EXPECT_EQ(e.cursor(), 6u);
  EXPECT_EQ(e.render(), "\r\x1b[K> echo h\xc3\xa9\x1b[1D");
  type(e, "\x1b[C\x7f");
  EXPECT_EQ(e.line(), "echo h");
}
