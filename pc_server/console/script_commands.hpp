#pragma once
// The console's commands of scripts: wait, expect, echo, quit/exit.
#include "pc_server/console/command_family.hpp"

namespace inspect::server {

class Console;

class ScriptCommands : public CommandFamily {
 public:
  explicit ScriptCommands(Console& console) : c_(console) {}
  std::vector<ConsoleCommand> commands() override;

 private:
  bool cmdWait(const CommandArgs& a);
  bool cmdExpect(const CommandArgs& a);
  bool cmdEcho(const CommandArgs& a);
  bool cmdQuit(const CommandArgs& a);
  Console& c_;
};

}  // namespace inspect::server
