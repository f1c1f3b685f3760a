#pragma once
// The console's commands of gas inspection and alarms: inspect, alarms, ack (docs/gas.md).
#include "pc_server/console/command_family.hpp"

namespace inspect::server {

class Console;

class GasCommands : public CommandFamily {
 public:
  explicit GasCommands(Console& console) : c_(console) {}
  std::vector<ConsoleCommand> commands() override;

 private:
  bool cmdInspect(const CommandArgs& a);
  bool cmdAlarms(const CommandArgs& a);
  bool cmdAck(const CommandArgs& a);
  Console& c_;
};

}  // namespace inspect::server
