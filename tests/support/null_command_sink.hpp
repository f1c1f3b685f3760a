#pragma once
// A CommandSink that sends nothing: for tests of a console or a bridge that
// read only what it prints or answers, with no robot link under it.
#include <cstdint>
#include <string>

#include "pc_server/link/command_sink.hpp"

namespace inspect::test {

class NullCommandSink : public server::CommandSink {
 public:
  uint64_t setTeleop(const std::string&, double, double, double) override { return 0; }
  void clearTeleop(const std::string&) override {}
  uint64_t sendCommand(const std::string&, v1::Command) override { return 0; }
  void consoleAlive() override {}
};

}  // namespace inspect::test
