#pragma once
// A family of console commands: one class per family, in its own pair of
// files (MAVSDK's one layout per plugin is the model), registered with the
// Console in the order `help` lists them. A family holds its own state (the
// tuning host's, for instance) and reaches the robots only through the
// Console's session: its operator service, its output and its waits
// (console.hpp, "For the command families").
#include <functional>
#include <vector>

#include "pc_server/console/command_args.hpp"

namespace inspect::server {

/// One command: its forms of typed arguments (command_args.hpp: the syntax,
/// the argument errors and completion come from them), its help, its handler.
struct ConsoleCommand {
  using Handler = std::function<bool(const CommandArgs& a)>;
  const char* name;
  std::vector<CommandForm> forms;
  const char* summary;
  const char* details;
  Handler run;
};

class CommandFamily {
 public:
  virtual ~CommandFamily() = default;
  /// The family's commands, their handlers bound to this family.
  virtual std::vector<ConsoleCommand> commands() = 0;
};

/// A handler that calls `family`'s member `m`.
template <class Family>
ConsoleCommand::Handler handler(Family* family, bool (Family::*m)(const CommandArgs&)) {
  return [family, m](const CommandArgs& a) { return (family->*m)(a); };
}

/// The forms of a command that takes no arguments: one empty form.
inline std::vector<CommandForm> noArguments() { return {CommandForm{}}; }

}  // namespace inspect::server
