// The console's command table (the families' commands, console.cpp): the help,
// the checks of its forms and the completion built from it (docs/console.md).
#include "pc_server/console/console.hpp"

#include <algorithm>
#include <map>

#include "pc_server/console/text_util.hpp"

namespace inspect::server {

using Source = ArgSpec::Source;

const ConsoleCommand* Console::findCommand(const std::string& name) const {
  for (const auto& c : table_)
    if (name == c.name) return &c;
  return nullptr;
}

std::string Console::helpText(const std::string& command) const {
  if (command.empty()) {
    std::string s = "commands:\n";
    for (const auto& c : table_) {
      if (std::string(c.name) == "exit") continue;
      const std::string syntax = commandSyntax(c.name, c.forms);
      s += syntax.size() <= 30 ? "  " + padRight(syntax, 30) + " " + c.summary + "\n"
                               : "  " + syntax + "\n  " + std::string(31, ' ') + c.summary + "\n";
    }
    s += "'help <command>' explains one; '#' starts a comment; 'try <command>' runs a command\n"
         "whose failure (e.g. an expected rejection) should not fail a script.\n";
    return s;
  }
  const ConsoleCommand* c = findCommand(command);
  if (!c) return "";
  // One line per form: "ptz <pan_deg> <tilt_deg>", then "ptz home".
  std::string s;
  for (const auto& f : formSyntaxes(c->name, c->forms)) s += f + "\n";
  return s + "  " + c->summary + "\n" + c->details;
}

std::string Console::tableProblems() const {
  std::string out;
  for (const auto& c : table_)
    if (std::string p = formProblems(c.name, c.forms); !p.empty()) out += p + "\n";
  return out;
}

std::vector<std::string> Console::completions(const std::string& partial_line) const {
  std::vector<std::string> done = splitWords(partial_line);
  const bool at_blank = !partial_line.empty() && (partial_line.back() == ' ' || partial_line.back() == '\t');
  const std::string partial = at_blank || done.empty() ? "" : done.back();
  if (!at_blank && !done.empty()) done.pop_back();
  const bool tried = !done.empty() && done.front() == "try";  // 'try <command>'
  if (tried) done.erase(done.begin());
  std::vector<std::string> names;
  if (!tried) names.push_back("try");
  for (const auto& c : table_) names.push_back(c.name);
  if (done.empty()) {
    std::vector<std::string> out;
    for (const auto& n : names)
      if (n.compare(0, partial.size(), partial) == 0) out.push_back(n);
    std::sort(out.begin(), out.end());
    return out;
  }
  const ConsoleCommand* c = findCommand(done.front() == "?" ? "help" : done.front());
  if (!c) return {};
  std::vector<std::string> robots;
  for (const auto& r : registry_.snapshots(clock_->nowNs())) robots.push_back(r.id);
  const std::map<ArgSpec::Source, std::vector<std::string>> dynamic{{Source::kCommands, names},
                                                                    {Source::kRobots, robots}};
  return completeArgs(c->forms, {done.begin() + 1, done.end()}, partial, dynamic);
}

}  // namespace inspect::server
