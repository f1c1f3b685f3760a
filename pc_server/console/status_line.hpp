#pragma once
// The one-line robot status of the console (`status` and the live bottom line).
#include <optional>
#include <string>

#include "pc_server/link/robot_registry.hpp"

namespace inspect::server {

class VideoHub;

/// Names of the set Fault bits ("LINK_LOST,SERIAL_DOWN"), or "none".
std::string faultNames(uint32_t faults);

/// E.g. "robot1 | TELEOP | v +0.30 w +0.00 | x 1.20 y 0.00 th +0.00 | us 1.23 2.01 -- 0.88 | faults none |
/// tlm 50 Hz | serial ok". `snap` empty = the robot never connected.
/// With `video`, the stream's live figures are appended:
/// "| video 30/30 fps 1480 kbit/s loss 0.0% lat 38 ms".
std::string statusLine(const std::string& robot_id, const std::optional<RobotSnapshot>& snap,
                       const VideoHub* video = nullptr);

/// The `video stats` text: receiver figures and counters, the SDP file, and
/// the robot's encoder figures from telemetry.
std::string videoReport(const std::string& robot_id, const std::optional<RobotSnapshot>& snap, const VideoHub* video);

/// True when the status deserves attention (e-stop, failsafe, faults, disconnected).
bool statusIsAlarm(const std::optional<RobotSnapshot>& snap);

}  // namespace inspect::server
