#pragma once
// The console's commands of recorded runs: record, runs, run, report, export,
// replay (docs/recording.md).
#include <optional>
#include <string>
#include <utility>

#include "pc_server/console/command_family.hpp"
#include "shared/catalog/catalog.hpp"

namespace inspect::server {

class Console;

class RunCommands : public CommandFamily {
 public:
  explicit RunCommands(Console& console) : c_(console) {}
  std::vector<ConsoleCommand> commands() override;

 private:
  bool cmdRecord(const CommandArgs& a);
  bool cmdRuns(const CommandArgs& a);
  bool cmdRun(const CommandArgs& a);
  bool cmdReport(const CommandArgs& a);
  bool cmdExport(const CommandArgs& a);
  bool cmdReplay(const CommandArgs& a);
  Console& c_;
};

/// A run of the catalog and its directory; prints why not (as `cmd`) on the
/// console when there is none (also `identify`'s).
std::optional<std::pair<catalog::RunDetail, std::string>> findRun(Console& c, const std::string& cmd,
                                                                  const std::string& id);

}  // namespace inspect::server
