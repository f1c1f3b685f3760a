#include "pc_server/console/command_args.hpp"

#include <algorithm>
#include <cmath>
#include <set>

#include "shared/util/number_text.hpp"
#include "shared/util/text_parse.hpp"

namespace inspect::server {

namespace args {

ArgSpec keyword(const std::string& word, const std::string& noun) {
  ArgSpec a;
  a.kind = ArgSpec::Kind::kKeyword;
  a.name = a.shown = word;
  a.words = {word};
  a.noun = noun;
  return a;
}

ArgSpec subcommand(const std::string& word, const std::string& noun) { return keyword(word, noun); }

ArgSpec choice(const std::string& name, std::vector<std::string> words, const std::string& noun) {
  ArgSpec a;
  a.kind = ArgSpec::Kind::kChoice;
  a.name = name;
  for (const auto& w : words) a.shown += (a.shown.empty() ? "" : "|") + w;
  a.words = std::move(words);
  a.noun = noun;
  return a;
}

ArgSpec number(const std::string& name) {
  ArgSpec a;
  a.kind = ArgSpec::Kind::kNumber;
  a.name = name;
  a.shown = "<" + name + ">";
  a.noun = "number";
  return a;
}

ArgSpec integer(const std::string& name, const std::string& noun) {
  ArgSpec a = number(name);
  a.kind = ArgSpec::Kind::kInteger;
  a.noun = noun;
  return a;
}

ArgSpec size(const std::string& name) {
  ArgSpec a;
  a.kind = ArgSpec::Kind::kSize;
  a.name = name;
  a.shown = "<W>x<H>";
  return a;
}

ArgSpec word(const std::string& name, const std::string& noun) {
  ArgSpec a;
  a.kind = ArgSpec::Kind::kWord;
  a.name = name;
  a.shown = "<" + name + ">";
  a.noun = noun;
  return a;
}

ArgSpec words(const std::string& shown) {
  ArgSpec a;
  a.kind = ArgSpec::Kind::kWords;
  a.name = "words";
  a.shown = shown;
  a.optional = true;
  return a;
}

ArgSpec rest(const std::string& name, const std::string& shown) {
  ArgSpec a;
  a.kind = ArgSpec::Kind::kRest;
  a.name = name;
  a.shown = shown.empty() ? "<" + name + ">" : shown;
  return a;
}

ArgSpec keyValues(const std::string& name, const std::string& shown, std::vector<ArgSpec> keys) {
  ArgSpec a;
  a.kind = ArgSpec::Kind::kKeyValues;
  a.name = name;
  a.shown = shown;
  a.keys = std::move(keys);
  return a;
}

ArgSpec opt(ArgSpec a) {
  a.optional = true;
  return a;
}

ArgSpec within(ArgSpec a, double lo, double hi, const std::string& unit) {
  a.ranged = true;
  a.lo = lo;
  a.hi = hi;
  a.unit = unit;
  return a;
}

ArgSpec wanting(ArgSpec a, const std::string& want) {
  a.want = want;
  return a;
}

ArgSpec completing(ArgSpec a, ArgSpec::Source source) {
  a.completes = source;
  return a;
}

}  // namespace args

const std::string& CommandArgs::text(const std::string& name) const {
  static const std::string kNone;
  const auto it = values_.find(name);
  return it == values_.end() ? kNone : it->second.text;
}

std::optional<double> CommandArgs::number(const std::string& name) const {
  const auto it = values_.find(name);
  return it == values_.end() ? std::nullopt : it->second.number;
}

const std::vector<std::string>& CommandArgs::list(const std::string& name) const {
  static const std::vector<std::string> kNone;
  const auto it = values_.find(name);
  return it == values_.end() ? kNone : it->second.list;
}

namespace {

using Kind = ArgSpec::Kind;

struct Word {
  std::string text;
  std::size_t at;  // offset in the line
};

std::vector<Word> wordsOf(const std::string& line) {
  std::vector<Word> out;
  std::size_t i = 0;
  const auto blank = [&](std::size_t k) { return line[k] == ' ' || line[k] == '\t' || line[k] == '\r'; };
  while (i < line.size()) {
    while (i < line.size() && blank(i)) ++i;
    const std::size_t start = i;
    while (i < line.size() && !blank(i)) ++i;
    if (i > start) out.push_back({line.substr(start, i - start), start});
  }
  return out;
}

std::string countWord(std::size_t n) {
  static const char* kWords[] = {"no", "one", "two", "three", "four", "five", "six"};
  return n < 7 ? kWords[n] : std::to_string(n);
}

bool multiWord(Kind k) { return k == Kind::kWords || k == Kind::kRest || k == Kind::kKeyValues; }

bool leadsByWord(const CommandForm& f) {
  return !f.args.empty() && (f.args[0].kind == Kind::kKeyword || f.args[0].kind == Kind::kChoice);
}

std::optional<std::pair<long long, long long>> parseSize(const std::string& s) {
  const auto x = s.find('x');
  if (x == std::string::npos) return std::nullopt;
  const auto w = util::parseInteger(s.substr(0, x));
  const auto h = util::parseInteger(s.substr(x + 1));
  if (!w || !h) return std::nullopt;
  return std::make_pair(*w, *h);
}

/// Whether `w` has the argument's type (not its range).
bool fits(const ArgSpec& a, const std::string& w) {
  switch (a.kind) {
    case Kind::kKeyword:
    case Kind::kChoice: return std::find(a.words.begin(), a.words.end(), w) != a.words.end();
    case Kind::kNumber: return util::parseNumber(w).has_value();
    case Kind::kInteger: return util::parseInteger(w).has_value();
    case Kind::kSize: return parseSize(w).has_value();
    default: return true;
  }
}

/// Why `w` is not a value of `a` (type or range); "" when it is.
std::string valueError(const ArgSpec& a, const std::string& w) {
  if (!fits(a, w)) {
    switch (a.kind) {
      case Kind::kNumber: return "'" + w + "' is not a number";
      case Kind::kInteger: return "'" + w + "' is not a whole number";
      case Kind::kSize: return "'" + w + "' is not <W>x<H>";
      case Kind::kChoice:
        return "unknown " + (a.noun.empty() ? a.name : a.noun) + " '" + w + "' (" + util::alternatives(a.words) + ")";
      default: return "'" + w + "' is not " + a.shown;
    }
  }
  if (a.ranged && (a.kind == Kind::kNumber || a.kind == Kind::kInteger)) {
    const double v = a.kind == Kind::kInteger ? static_cast<double>(*util::parseInteger(w)) : *util::parseNumber(w);
    if (!(v >= a.lo && v <= a.hi))
      return w + (a.unit.empty() ? "" : " " + a.unit) + " is outside [" + util::fmtShort(a.lo) + ", " +
             util::fmtShort(a.hi) + "]";
  }
  return "";
}

const ArgSpec* keyOf(const ArgSpec& a, const std::string& key) {
  for (const auto& k : a.keys)
    if (k.name == key) return &k;
  return nullptr;
}

/// Why the word is not one of `a`'s key=value pairs ("" when it is):
/// "'frob' is not key=value", "unknown option 'colour' (ref, radius ... or start)",
/// "evals=5: expected a number in [10, 100000]", "ref=spiral: expected circle, line or waypoints".
std::string keyValueError(const ArgSpec& a, const std::string& w) {
  std::string k, v;
  if (!util::splitKeyValue(w, k, v)) return "'" + w + "' is not key=value";
  const ArgSpec* key = keyOf(a, k);
  if (!key) {
    std::vector<std::string> names;
    for (const auto& o : a.keys) names.push_back(o.name);
    return "unknown option '" + k + "' (" + util::alternatives(names) + ")";
  }
  if (valueError(*key, v).empty()) return "";
  const bool fraction = key->kind == Kind::kInteger && util::parseNumber(v) && !util::parseInteger(v);
  const std::string what = fraction ? "a whole number" : "a number";
  switch (key->kind) {
    case Kind::kNumber:
    case Kind::kInteger:
      return w + ": expected " + what +
             (key->ranged ? " in [" + util::fmtShort(key->lo) + ", " + util::fmtShort(key->hi) + "]" : "");
    case Kind::kChoice: return w + ": expected " + util::alternatives(key->words);
    default: return w + ": expected " + key->shown;
  }
}

/// How a form's syntax shows the argument.
std::string shownInSyntax(const ArgSpec& a) {
  if (!a.optional || a.kind == Kind::kWords) return a.shown;
  std::string s = a.shown;
  if (s.size() > 2 && s.front() == '<' && s.back() == '>' && s.find('>') == s.size() - 1) s = s.substr(1, s.size() - 2);
  return "[" + s + "]";
}

std::string formSyntax(const std::string& command, const CommandForm& f) {
  std::string s = command;
  for (const auto& a : f.args) s += " " + shownInSyntax(a);
  return s;
}

/// A single form's count error: "needs two numbers: drive <v_m_s> <w_rad_s>".
std::string countError(const std::string& command, const CommandForm& f) {
  const std::string syntax = formSyntax(command, f);
  if (f.args.empty()) return "takes no arguments";
  std::string noun;
  std::size_t min = 0;
  for (const auto& a : f.args) {
    if (a.noun.empty() || multiWord(a.kind) || (!noun.empty() && a.noun != noun)) return "syntax: " + syntax;
    noun = a.noun;
    if (!a.optional) ++min;
  }
  const std::size_t max = f.args.size();
  if (min == 0 && max == 1) return "takes at most one " + noun + ": " + syntax;
  const std::string plural = noun + (max > 1 ? "s" : "");
  if (min == max) return "needs " + countWord(min) + " " + plural + ": " + syntax;
  return "needs " + countWord(min) + (max == min + 1 ? " or " : " to ") + countWord(max) + " " + plural + ": " + syntax;
}

struct Attempt {
  std::optional<CommandArgs> args;
  bool count_error = false;     // too few or too many words
  bool in_key_values = false;   // value_error is about one of a kKeyValues' pairs
  std::string value_error;      // a word of the wrong type or out of range
  const ArgSpec* failed = nullptr;
  std::string failed_word;
};

Attempt tryForm(const CommandForm& f, const std::vector<Word>& words, const std::string& line) {
  Attempt r;
  CommandArgs out;
  std::size_t j = 0;
  // Words an optional argument let pass: if one is left over, its error says more than the count.
  std::map<std::size_t, std::pair<const ArgSpec*, std::string>> passed;
  for (const auto& a : f.args) {
    if (multiWord(a.kind)) {
      if (j == words.size()) {
        if (a.optional) continue;
        r.count_error = true;
        return r;
      }
      out.setText(a.name, line.substr(words[j].at));
      for (; j < words.size(); ++j) {
        const std::string& w = words[j].text;
        if (a.kind == Kind::kKeyValues && !a.keys.empty()) {
          if (std::string why = keyValueError(a, w); !why.empty()) {
            r.failed = &a;
            r.failed_word = w;
            r.value_error = std::move(why);
            r.in_key_values = true;
            return r;
          }
          std::string k, v;
          util::splitKeyValue(w, k, v);
          const ArgSpec& key = *keyOf(a, k);
          out.setText(a.name + "." + k, v);  // a key given twice: the last value
          if (key.kind == Kind::kNumber || key.kind == Kind::kInteger) out.setNumber(a.name + "." + k, *util::parseNumber(v));
        }
        out.addWord(a.name, w);
      }
      continue;
    }
    if (j == words.size()) {
      if (a.optional) continue;
      r.count_error = true;
      return r;
    }
    const std::string& w = words[j].text;
    if (!fits(a, w)) {
      if (a.optional) {
        if (a.kind != Kind::kKeyword) passed[j] = {&a, valueError(a, w)};
        continue;
      }
      r.failed = &a;
      r.failed_word = w;
      if (a.kind == Kind::kKeyword)
        r.count_error = true;  // a missing keyword reads as the syntax
      else
        r.value_error = valueError(a, w);
      return r;
    }
    if (std::string why = valueError(a, w); !why.empty()) {
      r.failed = &a;
      r.failed_word = w;
      r.value_error = std::move(why);
      return r;
    }
    out.setText(a.name, w);
    if (a.kind == Kind::kNumber) out.setNumber(a.name, *util::parseNumber(w));
    if (a.kind == Kind::kInteger) out.setNumber(a.name, static_cast<double>(*util::parseInteger(w)));
    if (a.kind == Kind::kSize) {
      const auto wh = *parseSize(w);
      out.setNumber(a.name + ".w", static_cast<double>(wh.first));
      out.setNumber(a.name + ".h", static_cast<double>(wh.second));
    }
    ++j;
  }
  if (j < words.size()) {
    if (const auto p = passed.find(j); p != passed.end()) {
      r.failed = p->second.first;
      r.failed_word = words[j].text;
      r.value_error = p->second.second;
    } else {
      r.count_error = true;
    }
    return r;
  }
  r.args = std::move(out);
  return r;
}

}  // namespace

std::vector<std::string> formSyntaxes(const std::string& command, const std::vector<CommandForm>& forms) {
  std::vector<std::string> out;
  for (const auto& f : forms) out.push_back(formSyntax(command, f));
  return out;
}

std::string commandSyntax(const std::string& command, const std::vector<CommandForm>& forms) {
  std::string s;
  for (const auto& f : formSyntaxes(command, forms)) s += (s.empty() ? "" : " | ") + f;
  return s.empty() ? command : s;
}

std::variant<CommandArgs, std::string> parseCommandArgs(const std::string& command,
                                                        const std::vector<CommandForm>& forms,
                                                        const std::string& line_after_name) {
  const auto words = wordsOf(line_after_name);
  std::vector<Attempt> attempts;
  for (std::size_t i = 0; i < forms.size(); ++i) {
    Attempt a = tryForm(forms[i], words, line_after_name);
    if (a.args) {
      a.args->form = i;
      for (const auto& w : words) a.args->words.push_back(w.text);
      a.args->rest = util::trim(line_after_name);
      return std::move(*a.args);
    }
    attempts.push_back(std::move(a));
  }
  if (forms.empty()) return words.empty() ? std::variant<CommandArgs, std::string>(CommandArgs{}) : "takes no arguments";
  if (forms.size() == 1) return attempts[0].count_error ? countError(command, forms[0]) : attempts[0].value_error;
  const std::string syntax = "syntax: " + commandSyntax(command, forms);
  // Several forms: the one the first word selects says what is wrong with the rest.
  for (std::size_t i = 0; i < forms.size(); ++i) {
    if (!leadsByWord(forms[i]) || words.empty() || !fits(forms[i].args[0], words[0].text)) continue;
    const Attempt& a = attempts[i];
    if (a.count_error || !a.failed) return syntax;
    if (!a.failed->want.empty()) return words[0].text + " '" + a.failed_word + "': want " + a.failed->want;
    return a.value_error;
  }
  // A form of key=value pairs that the line fits but for one pair says which.
  const auto kv = std::find_if(attempts.begin(), attempts.end(), [](const Attempt& a) { return a.in_key_values; });
  if (kv != attempts.end()) return kv->value_error;
  const bool all_by_word = std::all_of(forms.begin(), forms.end(), leadsByWord);
  if (!all_by_word || words.empty()) return syntax;
  // "unknown subcommand 'frob' (show, set, push, revert, export or import)"
  std::vector<std::string> leading;
  for (const auto& f : forms)
    for (const auto& w : f.args[0].words)
      if (std::find(leading.begin(), leading.end(), w) == leading.end()) leading.push_back(w);
  const std::string& noun = forms[0].args[0].noun;
  return "unknown " + (noun.empty() ? "" : noun + " ") + "'" + words[0].text + "' (" + util::alternatives(leading) + ")";
}

std::string formProblems(const std::string& command, const std::vector<CommandForm>& forms) {
  for (const auto& f : forms) {
    std::set<std::string> names;
    for (std::size_t i = 0; i < f.args.size(); ++i) {
      const ArgSpec& a = f.args[i];
      if (!names.insert(a.name).second) return formSyntax(command, f) + ": two arguments named '" + a.name + "'";
      if (multiWord(a.kind) && i + 1 != f.args.size())
        return formSyntax(command, f) + ": '" + a.name + "' takes the rest of the line but is not last";
    }
  }
  return "";
}

std::vector<std::string> completeArgs(const std::vector<CommandForm>& forms, const std::vector<std::string>& done,
                                      const std::string& partial,
                                      const std::map<ArgSpec::Source, std::vector<std::string>>& dynamic) {
  std::set<std::string> out;
  const auto offer = [&](const ArgSpec& a) {
    std::vector<std::string> candidates = a.words;
    if (const auto d = dynamic.find(a.completes); a.completes != ArgSpec::Source::kNone && d != dynamic.end())
      candidates.insert(candidates.end(), d->second.begin(), d->second.end());
    for (const auto& c : candidates)
      if (c.compare(0, partial.size(), partial) == 0) out.insert(c);
  };
  const auto offerKeys = [&](const ArgSpec& a) {
    std::string k, v;
    if (!util::splitKeyValue(partial, k, v)) {
      for (const auto& key : a.keys)
        if (key.name.compare(0, partial.size(), partial) == 0) out.insert(key.name + "=");
      return;
    }
    if (const ArgSpec* key = keyOf(a, k))
      for (const auto& w : key->words)
        if (w.compare(0, v.size(), v) == 0) out.insert(k + "=" + w);
  };
  for (const auto& f : forms) {
    std::size_t j = 0;
    bool ok = true;
    std::size_t i = 0;
    for (; i < f.args.size() && j < done.size(); ++i) {
      const ArgSpec& a = f.args[i];
      if (a.kind == Kind::kKeyValues && !a.keys.empty()) {
        j = done.size();  // the pairs go on to the end of the line: offer the keys again
        break;
      }
      if (multiWord(a.kind)) {
        j = done.size();
        ok = false;  // free text: nothing to offer
        break;
      }
      if (fits(a, done[j])) {
        ++j;
      } else if (!a.optional) {
        ok = false;
        break;
      }
    }
    if (!ok || j < done.size()) continue;
    // The next word may fill any optional argument up to and including the next required one.
    for (; i < f.args.size(); ++i) {
      if (f.args[i].kind == Kind::kKeyValues) offerKeys(f.args[i]);
      offer(f.args[i]);
      if (!f.args[i].optional) break;
    }
  }
  return {out.begin(), out.end()};
}

}  // namespace inspect::server
