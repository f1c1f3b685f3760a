#pragma once
// The console's session commands: help, robots, select, status, control.
#include "pc_server/console/command_family.hpp"

namespace inspect::server {

class Console;

class SessionCommands : public CommandFamily {
 public:
  explicit SessionCommands(Console& console) : c_(console) {}
  std::vector<ConsoleCommand> commands() override;

 private:
  bool cmdHelp(const CommandArgs& a);
  bool cmdRobots(const CommandArgs& a);
  bool cmdSelect(const CommandArgs& a);
  bool cmdStatus(const CommandArgs& a);
  bool cmdControl(const CommandArgs& a);
  Console& c_;
};

}  // namespace inspect::server
