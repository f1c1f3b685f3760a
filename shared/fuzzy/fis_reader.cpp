#include "shared/fuzzy/fis_reader.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <utility>
#include <vector>

#include "shared/fuzzy/fis_error.hpp"

namespace inspect::fuzzy {

namespace {

struct Entry {
  std::string key;
  std::string value;
  int line = 0;
};

struct Section {
  std::string name;  // without brackets
  int line = 0;
  std::vector<Entry> entries;
  std::vector<std::pair<int, std::string>> raw_lines;  // for [Rules]
};

std::string_view trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string_view::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

bool isComment(std::string_view t) {
  return !t.empty() && (t.front() == '%' || t.front() == '#' || t.substr(0, 2) == "//");
}

std::string_view commentText(std::string_view t) {
  t = t.substr(t.substr(0, 2) == "//" ? 2 : 1);
  return trim(t);
}

// Reads .fis text step by step; every error carries the current file and line.
class Parser {
 public:
  Parser(std::string_view text, std::string file) : text_(text), file_(std::move(file)) {}

  Fis run();

 private:
  [[noreturn]] void fail(int line, const std::string& msg) const {
    throw FisError(file_ + ":" + std::to_string(line) + ": " + msg);
  }

  void split();
  const Section* find(const std::string& name) const {
    for (const auto& s : sections_) {
      if (s.name == name) return &s;
    }
    return nullptr;
  }
  const Entry* entry(const Section& s, const std::string& key) const {
    for (const auto& e : s.entries) {
      if (e.key == key) return &e;
    }
    return nullptr;
  }
  const Entry& require(const Section& s, const std::string& key) const {
    const Entry* e = entry(s, key);
    if (!e) fail(s.line, "[" + s.name + "] has no " + key + "=");
    return *e;
  }

  std::string quoted(const Entry& e) const;
  long integer(const Entry& e, long min, long max) const;
  double number(std::string_view tok, int line, const std::string& what) const;
  std::vector<double> numberList(std::string_view s, int line, const std::string& what) const;
  template <typename T>
  T method(const Section& sys, const std::string& key, std::optional<T> (*parse)(std::string_view),
           const std::string& choices) const {
    const Entry& e = require(sys, key);
    const std::string v = quoted(e);
    auto r = parse(v);
    if (!r) fail(e.line, key + ": unsupported '" + v + "' (supported: " + choices + ")");
    return *r;
  }
  Variable variable(const Section& s, bool is_output, std::size_t index);
  Rule rule(int line, std::string_view text, std::size_t index) const;
  int problemLine(const FisProblem& p) const;

  std::string_view text_;
  std::string file_;
  std::vector<std::string> comments_;
  std::vector<Section> sections_;
  // Where things were, so that validation problems can name their line.
  std::map<std::pair<int, std::size_t>, const Section*> var_sections_;  // (0 input / 1 output, index)
  std::vector<int> rule_lines_;
};

void Parser::split() {
  std::size_t pos = 0;
  int line_no = 0;
  Section* current = nullptr;
  while (pos <= text_.size()) {
    const std::size_t nl = text_.find('\n', pos);
    const std::string_view raw = text_.substr(pos, nl == std::string_view::npos ? std::string_view::npos : nl - pos);
    pos = nl == std::string_view::npos ? text_.size() + 1 : nl + 1;
    ++line_no;
    const std::string_view t = trim(raw);
    if (t.empty()) continue;
    if (isComment(t)) {
      if (sections_.empty()) comments_.emplace_back(commentText(t));
      continue;
    }
    if (t.front() == '[') {
      if (t.back() != ']') fail(line_no, "section header needs a closing ']'");
      const std::string name(trim(t.substr(1, t.size() - 2)));
      if (find(name)) fail(line_no, "section [" + name + "] appears twice");
      sections_.push_back(Section{name, line_no, {}, {}});
      current = &sections_.back();
      continue;
    }
    if (!current) fail(line_no, "text before the first section; a .fis file starts with [System]");
    if (current->name == "Rules") {
      current->raw_lines.emplace_back(line_no, std::string(t));
      continue;
    }
    const auto eq = t.find('=');
    if (eq == std::string_view::npos) fail(line_no, "expected Key=value in [" + current->name + "]");
    Entry e{std::string(trim(t.substr(0, eq))), std::string(trim(t.substr(eq + 1))), line_no};
    if (e.key.empty()) fail(line_no, "empty key before '='");
    if (entry(*current, e.key)) fail(line_no, e.key + " appears twice in [" + current->name + "]");
    current->entries.push_back(std::move(e));
  }
}

std::string Parser::quoted(const Entry& e) const {
  const std::string_view v = e.value;
  if (v.size() < 2 || v.front() != '\'' || v.back() != '\'') fail(e.line, e.key + ": expected a quoted 'text'");
  const std::string_view inner = v.substr(1, v.size() - 2);
  if (inner.find('\'') != std::string_view::npos) fail(e.line, e.key + ": a quote inside the text is not supported");
  return std::string(inner);
}

long Parser::integer(const Entry& e, long min, long max) const {
  long v = 0;
  const char* b = e.value.data();
  const char* end = b + e.value.size();
  auto [p, ec] = std::from_chars(b, end, v);
  if (ec != std::errc() || p != end) fail(e.line, e.key + ": expected a whole number, got '" + e.value + "'");
  if (v < min || v > max) {
    fail(e.line, e.key + ": " + std::to_string(v) + " is outside [" + std::to_string(min) + ", " + std::to_string(max) + "]");
  }
  return v;
}

double Parser::number(std::string_view tok, int line, const std::string& what) const {
  double v = 0;
  const char* b = tok.data();
  const char* end = b + tok.size();
  if (b != end && *b == '+') ++b;
  auto [p, ec] = std::from_chars(b, end, v);
  if (ec != std::errc() || p != end) fail(line, what + ": '" + std::string(tok) + "' is not a number");
  if (!std::isfinite(v)) fail(line, what + ": '" + std::string(tok) + "' is not a finite number");
  return v;
}

std::vector<double> Parser::numberList(std::string_view s, int line, const std::string& what) const {
  s = trim(s);
  if (s.size() < 2 || s.front() != '[' || s.back() != ']') fail(line, what + ": expected a list [a b ...]");
  s = s.substr(1, s.size() - 2);
  std::vector<double> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == ',')) ++i;
    if (i >= s.size()) break;
    std::size_t j = i;
    while (j < s.size() && s[j] != ' ' && s[j] != '\t' && s[j] != ',') ++j;
    out.push_back(number(s.substr(i, j - i), line, what));
    i = j;
  }
  return out;
}

Variable Parser::variable(const Section& s, bool is_output, std::size_t index) {
  var_sections_[{is_output ? 1 : 0, index}] = &s;
  Variable v;
  for (const auto& e : s.entries) {
    const bool known = e.key == "Name" || e.key == "Range" || e.key == "NumMFs" ||
                       (e.key.size() > 2 && e.key.compare(0, 2, "MF") == 0);
    if (!known) fail(e.line, "unknown key '" + e.key + "' in [" + s.name + "]");
  }
  v.name = quoted(require(s, "Name"));
  const Entry& range = require(s, "Range");
  const auto r = numberList(range.value, range.line, "Range");
  if (r.size() != 2) fail(range.line, "Range needs 2 numbers [min max], got " + std::to_string(r.size()));
  v.min = r[0];
  v.max = r[1];
  const long n = integer(require(s, "NumMFs"), 0, 10000);
  v.mfs.resize(static_cast<std::size_t>(n));
  std::vector<bool> seen(static_cast<std::size_t>(n), false);
  for (const auto& e : s.entries) {
    if (e.key.compare(0, 2, "MF") != 0 || e.key == "MF") continue;
    long k = 0;
    const char* b = e.key.data() + 2;
    const char* end = e.key.data() + e.key.size();
    auto [p, ec] = std::from_chars(b, end, k);
    if (ec != std::errc() || p != end) fail(e.line, "unknown key '" + e.key + "' in [" + s.name + "]");
    if (k < 1 || k > n) fail(e.line, e.key + ": NumMFs is " + std::to_string(n));
    // 'name':'type',[params]
    const std::string_view val = e.value;
    auto bad = [&]() { fail(e.line, e.key + ": expected 'name':'type',[parameters]"); };
    if (val.empty() || val.front() != '\'') bad();
    const auto q1 = val.find('\'', 1);
    if (q1 == std::string_view::npos) bad();
    std::string_view rest = trim(val.substr(q1 + 1));
    if (rest.empty() || rest.front() != ':') bad();
    rest = trim(rest.substr(1));
    if (rest.empty() || rest.front() != '\'') bad();
    const auto q2 = rest.find('\'', 1);
    if (q2 == std::string_view::npos) bad();
    const std::string type_name(rest.substr(1, q2 - 1));
    rest = trim(rest.substr(q2 + 1));
    if (rest.empty() || rest.front() != ',') bad();
    rest = trim(rest.substr(1));
    MembershipFunction mf;
    mf.name = std::string(val.substr(1, q1 - 1));
    const auto type = parseMfType(type_name);
    if (!type) {
      fail(e.line, e.key + ": unsupported membership function type '" + type_name +
                       "' (supported: trimf trapmf gaussmf gauss2mf gbellmf sigmf dsigmf psigmf smf zmf pimf constant linear)");
    }
    mf.type = *type;
    mf.params = numberList(rest, e.line, e.key);
    v.mfs[static_cast<std::size_t>(k - 1)] = std::move(mf);
    seen[static_cast<std::size_t>(k - 1)] = true;
  }
  for (std::size_t k = 0; k < seen.size(); ++k) {
    if (!seen[k]) fail(s.line, "[" + s.name + "] has NumMFs=" + std::to_string(n) + " but no MF" + std::to_string(k + 1));
  }
  return v;
}

Rule Parser::rule(int line, std::string_view text, std::size_t index) const {
  const std::string tag = "rule " + std::to_string(index + 1);
  auto bad = [&](const std::string& why) {
    fail(line, tag + ": " + why + " (expected 'in1 in2 ..., out1 ... (weight) : connection')");
  };
  const auto comma = text.find(',');
  const auto open = text.find('(');
  const auto close = text.find(')');
  const auto colon = text.find(':');
  if (comma == std::string_view::npos) bad("no ',' between inputs and outputs");
  if (open == std::string_view::npos || close == std::string_view::npos || close < open || open < comma) {
    bad("no '(weight)' after the outputs");
  }
  if (colon == std::string_view::npos || colon < close) bad("no ': connection' after the weight");

  auto ints = [&](std::string_view s, const char* what) {
    std::vector<int> out;
    std::size_t i = 0;
    while (i < s.size()) {
      while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
      if (i >= s.size()) break;
      std::size_t j = i;
      while (j < s.size() && s[j] != ' ' && s[j] != '\t') ++j;
      const std::string_view tok = s.substr(i, j - i);
      // fuzzylite writes indices as "1.000"; a fractional part would be one of
      // its hedges, which MATLAB does not have.
      double v = 0;
      auto [p, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
      if (ec != std::errc() || p != tok.data() + tok.size() || !std::isfinite(v)) {
        fail(line, tag + ": '" + std::string(tok) + "' is not a membership function index (" + what + ")");
      }
      if (v != std::trunc(v) || std::abs(v) > 1e6) {
        fail(line, tag + ": '" + std::string(tok) + "' is not a whole membership function index (" + what +
                       "; fractional indices are fuzzylite hedges, which MATLAB .fis files do not have)");
      }
      out.push_back(static_cast<int>(v));
      i = j;
    }
    return out;
  };
  Rule r;
  r.antecedent = ints(text.substr(0, comma), "inputs");
  r.consequent = ints(text.substr(comma + 1, open - comma - 1), "outputs");
  r.weight = number(trim(text.substr(open + 1, close - open - 1)), line, tag + ": weight");
  if (!trim(text.substr(close + 1, colon - close - 1)).empty()) bad("unexpected text between ')' and ':'");
  const std::string_view conn = trim(text.substr(colon + 1));
  if (conn == "1") {
    r.connection = Connection::kAnd;
  } else if (conn == "2") {
    r.connection = Connection::kOr;
  } else {
    fail(line, tag + ": connection must be 1 (AND) or 2 (OR), got '" + std::string(conn) + "'");
  }
  return r;
}

int Parser::problemLine(const FisProblem& p) const {
  using Where = FisProblem::Where;
  if (p.where == Where::kRule) return p.index < rule_lines_.size() ? rule_lines_[p.index] : 0;
  if (p.where == Where::kSystem) {
    const Section* sys = find("System");
    if (!sys) return 0;
    if (const Entry* e = entry(*sys, p.key)) return e->line;
    if (p.key == "NumRules") {
      if (const Section* rules = find("Rules")) return rules->line;
    }
    return sys->line;
  }
  auto it = var_sections_.find({p.where == Where::kOutput ? 1 : 0, p.index});
  if (it == var_sections_.end()) return 0;
  const Section& s = *it->second;
  if (p.mf) {
    if (const Entry* e = entry(s, "MF" + std::to_string(*p.mf + 1))) return e->line;
  }
  if (!p.key.empty()) {
    if (const Entry* e = entry(s, p.key)) return e->line;
  }
  return s.line;
}

Fis Parser::run() {
  split();
  const Section* sys = find("System");
  if (!sys) fail(1, "no [System] section; this is not a MATLAB .fis file");

  Fis fis;
  fis.comments = comments_;
  static const char* const kSystemKeys[] = {"Name",      "Type",      "Version",   "NumInputs",
                                            "NumOutputs", "NumRules",  "AndMethod", "OrMethod",
                                            "ImpMethod", "AggMethod", "DefuzzMethod", "DisableStructuralChecks"};
  for (const auto& e : sys->entries) {
    bool known = false;
    for (const char* k : kSystemKeys) known = known || e.key == k;
    if (!known) fail(e.line, "unknown key '" + e.key + "' in [System]");
  }
  fis.name = quoted(require(*sys, "Name"));
  {
    const Entry& e = require(*sys, "Type");
    const std::string t = quoted(e);
    const auto type = parseFisType(t);
    if (!type) fail(e.line, "Type: unsupported '" + t + "' (supported: mamdani, sugeno)");
    fis.type = *type;
  }
  if (const Entry* e = entry(*sys, "Version")) {
    fis.version = e->value;
    if (fis.version.empty()) fail(e->line, "Version is empty");
  }
  if (const Entry* e = entry(*sys, "DisableStructuralChecks")) {
    fis.disable_structural_checks = static_cast<int>(integer(*e, 0, 1));
  }
  const long num_in = integer(require(*sys, "NumInputs"), 0, 1000);
  const long num_out = integer(require(*sys, "NumOutputs"), 0, 1000);
  const Entry& num_rules_entry = require(*sys, "NumRules");
  const long num_rules = integer(num_rules_entry, 0, 1000000);
  fis.and_method = method<AndMethod>(*sys, "AndMethod", parseAndMethod, "min, prod");
  fis.or_method = method<OrMethod>(*sys, "OrMethod", parseOrMethod, "max, probor");
  fis.imp_method = method<ImpMethod>(*sys, "ImpMethod", parseImpMethod, "min, prod");
  fis.agg_method = method<AggMethod>(*sys, "AggMethod", parseAggMethod, "max, sum, probor");
  fis.defuzz_method = method<DefuzzMethod>(*sys, "DefuzzMethod", parseDefuzzMethod,
                                           "centroid, bisector, mom, som, lom, wtaver, wtsum");

  // Every section must be expected: [InputN]/[OutputN] within the counts.
  auto numbered = [&](const Section& s, const std::string& prefix, long count, const char* key) {
    if (s.name.size() <= prefix.size() || s.name.compare(0, prefix.size(), prefix) != 0) return false;
    long k = 0;
    const char* b = s.name.data() + prefix.size();
    const char* end = s.name.data() + s.name.size();
    auto [p, ec] = std::from_chars(b, end, k);
    if (ec != std::errc() || p != end) return false;
    if (k < 1 || k > count) fail(s.line, "[" + s.name + "]: " + key + " is " + std::to_string(count));
    return true;
  };
  for (const auto& s : sections_) {
    if (s.name == "System" || s.name == "Rules") continue;
    if (numbered(s, "Input", num_in, "NumInputs") || numbered(s, "Output", num_out, "NumOutputs")) continue;
    fail(s.line, "unknown section [" + s.name + "]");
  }
  for (long i = 1; i <= num_in; ++i) {
    const Section* s = find("Input" + std::to_string(i));
    if (!s) fail(entry(*sys, "NumInputs")->line, "NumInputs=" + std::to_string(num_in) + " but there is no [Input" + std::to_string(i) + "]");
    fis.inputs.push_back(variable(*s, false, static_cast<std::size_t>(i - 1)));
  }
  for (long i = 1; i <= num_out; ++i) {
    const Section* s = find("Output" + std::to_string(i));
    if (!s) fail(entry(*sys, "NumOutputs")->line, "NumOutputs=" + std::to_string(num_out) + " but there is no [Output" + std::to_string(i) + "]");
    fis.outputs.push_back(variable(*s, true, static_cast<std::size_t>(i - 1)));
  }
  const Section* rules = find("Rules");
  if (!rules) fail(sys->line, "no [Rules] section");
  for (const auto& [line, text] : rules->raw_lines) {
    rule_lines_.push_back(line);
    fis.rules.push_back(rule(line, text, fis.rules.size()));
  }
  if (static_cast<long>(fis.rules.size()) != num_rules) {
    fail(num_rules_entry.line, "NumRules=" + std::to_string(num_rules) + " but [Rules] has " +
                                   std::to_string(fis.rules.size()) + " rule" + (fis.rules.size() == 1 ? "" : "s"));
  }

  const auto problems = fisProblems(fis);
  if (!problems.empty()) {
    const FisProblem& p = problems.front();
    const std::string more =
        problems.size() > 1 ? " (and " + std::to_string(problems.size() - 1) + " more problem" +
                                  (problems.size() > 2 ? "s" : "") + ")"
                            : "";
    fail(problemLine(p), p.message + more);
  }
  return fis;
}

}  // namespace

Fis parseFis(std::string_view text, const std::string& file_name) { return Parser(text, file_name).run(); }

Fis readFisFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FisError(path + ": cannot open file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parseFis(ss.str(), path);
}

}  // namespace inspect::fuzzy
