#pragma once
// What a robot is to the plant's SCADA (docs/sparkplug.md "Metrics"): its
// telemetry and Hello as Sparkplug metrics with their deadbands, and a gas
// alarm transition as the metrics of one event at the robot's time.
#include <cstdint>
#include <string>
#include <vector>

#include "inspect_robot/v1/link.pb.h"
#include "pc_server/sparkplug/sparkplug_config.hpp"
#include "pc_server/sparkplug/sparkplug_metric.hpp"

namespace inspect::server::sparkplug {

/// Every metric of a robot now (the order of its DBIRTH): pose, mode, faults,
/// battery, speed, people, each gas channel's value and unit and its alarms
/// in force, the run being recorded ("" = none).
std::vector<Metric> deviceMetrics(const v1::Hello& hello, const v1::Telemetry& t, const std::string& run,
                                  const Deadbands& deadbands);

/// The writable metrics of DCMD (docs/sparkplug.md "Commands"), and the answer's.
inline constexpr const char* kCommandStop = "Commands/Stop";
inline constexpr const char* kCommandEStop = "Commands/E-Stop";
inline constexpr const char* kCommandResult = "Commands/Last Result";

/// A robot this server has no telemetry of (an earlier process's, in the
/// spool): the DBIRTH metrics of one alarm's level alone.
std::vector<Metric> alarmOnlyMetrics(const v1::GasAlarm& a);

/// The metric name of a channel's alarm level: "Gas/CH4/A1", ".../A2", ".../Sensor Fault".
std::string alarmMetricName(const std::string& channel, v1::GasAlarm::Level level);

/// One alarm transition as event metrics at `time_ms` (the robot's time of
/// the transition on the wall clock): the level's Boolean (raised = true),
/// the alarm's id and the reading at the transition. `historical`: a stored
/// transition delivered late.
std::vector<Metric> alarmEventMetrics(const v1::GasAlarm& a, uint64_t time_ms, bool historical);

}  // namespace inspect::server::sparkplug
