#pragma once
// The console's commands that move the robot and its camera: drive, teleop,
// track, goto, route, stop, estop, resume; video, ptz, snapshot, foxglove, sparkplug.
#include "pc_server/console/command_family.hpp"

namespace inspect::server {

class Console;

class MotionCommands : public CommandFamily {
 public:
  explicit MotionCommands(Console& console) : c_(console) {}
  std::vector<ConsoleCommand> commands() override;

 private:
  bool cmdDrive(const CommandArgs& a);
  bool cmdTeleop(const CommandArgs& a);
  bool cmdTrack(const CommandArgs& a);
  bool cmdGoto(const CommandArgs& a);
  bool cmdRoute(const CommandArgs& a);
  bool cmdStop(const CommandArgs& a);
  bool cmdEstop(const CommandArgs& a);
  bool cmdResume(const CommandArgs& a);
  bool cmdVideo(const CommandArgs& a);
  bool cmdPtz(const CommandArgs& a);
  bool cmdSnapshot(const CommandArgs& a);
  bool cmdFoxglove(const CommandArgs& a);
  bool cmdSparkplug(const CommandArgs&);
  Console& c_;
};

}  // namespace inspect::server
