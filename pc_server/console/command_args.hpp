#pragma once
// A console command's arguments as a table (docs/console.md "Arguments"):
// each command has one or more forms, each form a list of typed arguments
// (keyword, choice of words, number with an optional range, <W>x<H>, word,
// the rest of the line, key=value words). The words of a line are parsed
// once, from the table: the syntax in `help`, the completion of a partial
// line and every argument error ("needs two numbers: drive <v_m_s> <w_rad_s>",
// "'abc' is not a number", "unknown mode 'fast' (step or hold)", "syntax:
// ptz <pan_deg> <tilt_deg> | ptz home") are generated from it, the same for
// every command. What the handler gets is typed and named.
#include <cstddef>
#include <initializer_list>
#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace inspect::server {

struct ArgSpec {
  enum class Kind {
    kKeyword,    // a literal word: "take", "home" (a form's first keyword selects the form)
    kChoice,     // one of `words`: "step|hold"
    kNumber,     // a finite number; [lo, hi] checked here when `ranged`
    kInteger,    // a whole number; [lo, hi] checked here when `ranged`
    kSize,       // <W>x<H>, two whole numbers
    kWord,       // any one word: a robot id, a run id, a file
    kWords,      // any words, to the end of the line (zero or more)
    kRest,       // the rest of the line as written, one or more words
    kKeyValues,  // name=value words to the end of the line (one or more)
  };
  Kind kind = Kind::kWord;
  std::string name;                // handlers read the value by it; keywords: the word
  std::string shown;               // as the syntax shows it: "<v_m_s>", "step|hold"
  std::vector<std::string> words;  // kKeyword: the word; kChoice: the accepted words
  std::string noun;                // count errors: "needs one robot id" ("" = not countable)
  bool optional = false;
  bool ranged = false;
  double lo = 0.0, hi = 0.0;
  std::string unit;  // range errors: "-1 s is outside [0, 3600]"
  std::string want;  // value errors in a keyword form: "fps 'many': want 1 to 120"
  enum class Source { kNone, kCommands, kRobots } completes = Source::kNone;
  /// kKeyValues: the keys accepted, each a number, whole number, choice or
  /// word named by its key ("evals", "ref"); empty = any name=value, checked
  /// by the handler. Values are read as "<name>.<key>".
  std::vector<ArgSpec> keys;
};

namespace args {
ArgSpec keyword(const std::string& word, const std::string& noun = "");
/// A keyword that leads a form; `noun` names the kind in "unknown subcommand 'frob' (show, set ...)".
ArgSpec subcommand(const std::string& word, const std::string& noun = "subcommand");
ArgSpec choice(const std::string& name, std::vector<std::string> words, const std::string& noun = "");
ArgSpec number(const std::string& name);
ArgSpec integer(const std::string& name, const std::string& noun = "number");
ArgSpec size(const std::string& name);
ArgSpec word(const std::string& name, const std::string& noun = "");
ArgSpec words(const std::string& shown);
ArgSpec rest(const std::string& name, const std::string& shown = "");
ArgSpec keyValues(const std::string& name, const std::string& shown, std::vector<ArgSpec> keys = {});
/// The same argument, optional ("[<speed_m_s>]").
ArgSpec opt(ArgSpec a);
/// The same number, checked in [lo, hi] (`unit` names it in the error).
ArgSpec within(ArgSpec a, double lo, double hi, const std::string& unit = "");
/// The same argument, with the text of what a value should be.
ArgSpec wanting(ArgSpec a, const std::string& want);
/// The same word, completed from `source`.
ArgSpec completing(ArgSpec a, ArgSpec::Source source);
}  // namespace args

/// One way of writing a command: its arguments in order.
struct CommandForm {
  CommandForm() = default;
  CommandForm(std::initializer_list<ArgSpec> a) : args(a) {}
  std::vector<ArgSpec> args;
};

/// A line's arguments, parsed by a command's forms.
class CommandArgs {
 public:
  std::size_t form = 0;            // which form matched, in declaration order
  std::vector<std::string> words;  // the words after the command name
  std::string rest;                // the line after the command name, as written
  int line_no = 0;

  bool has(const std::string& name) const { return values_.count(name) > 0; }
  /// The word(s) given for `name` ("" when absent); a keyword's own word.
  const std::string& text(const std::string& name) const;
  /// A number, integer or size part ("name.w", "name.h") given for `name`.
  std::optional<double> number(const std::string& name) const;
  double number(const std::string& name, double fallback) const { return number(name).value_or(fallback); }
  /// kWords / kKeyValues: the words given for `name`.
  const std::vector<std::string>& list(const std::string& name) const;

  void setText(const std::string& name, std::string t) { values_[name].text = std::move(t); }
  void setNumber(const std::string& name, double v) { values_[name].number = v; }
  void addWord(const std::string& name, const std::string& w) { values_[name].list.push_back(w); }

 private:
  struct Value {
    std::string text;
    std::optional<double> number;
    std::vector<std::string> list;
  };
  std::map<std::string, Value> values_;
};

/// "drive <v_m_s> <w_rad_s>"; forms joined by " | ".
std::string commandSyntax(const std::string& command, const std::vector<CommandForm>& forms);
/// Each form's syntax on its own ("ptz <pan_deg> <tilt_deg>", "ptz home").
std::vector<std::string> formSyntaxes(const std::string& command, const std::vector<CommandForm>& forms);

/// The words of `line_after_name` parsed by the first form they fit; or the
/// error, without the "<command>: " prefix.
std::variant<CommandArgs, std::string> parseCommandArgs(const std::string& command,
                                                        const std::vector<CommandForm>& forms,
                                                        const std::string& line_after_name);

/// Why the forms cannot be parsed unambiguously ("" when they can): two
/// arguments of a form with one name (a keyword's name is its word), a
/// multi-word argument before the form's end.
std::string formProblems(const std::string& command, const std::vector<CommandForm>& forms);

/// The words that may come next after `done` (complete words) and start with
/// `partial`, from the forms' keywords, choices and keys ("evals=", "ref=line");
/// `dynamic` answers the
/// sources (robots, commands). Sorted, without duplicates.
std::vector<std::string> completeArgs(const std::vector<CommandForm>& forms, const std::vector<std::string>& done,
                                      const std::string& partial,
                                      const std::map<ArgSpec::Source, std::vector<std::string>>& dynamic);

}  // namespace inspect::server
