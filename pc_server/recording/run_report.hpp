#pragma once
// A recorded run's report: PNG plots (through the gnuplot helper) of the path,
// the speeds and people, the tracking errors and the gas channels, and a
// Markdown summary with the RunStats figures, the events and links to the
// plots and the run's files.
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "inspect_robot/v1/link.pb.h"
#include "shared/geometry/segment.hpp"

namespace inspect::server {

struct RunReportInput {
  std::string run_id, robot, name, outcome, started_utc, ended_utc;
  std::vector<v1::Telemetry> telemetry;                  // in arrival order
  std::vector<std::pair<double, std::string>> events;   // t_s, text
  std::vector<std::string> files;                        // paths to link (made relative to the report)

  std::vector<v1::GasChannelInfo> gas_channels;            // from the robot's Hello; empty = unknown (names gas0..)
  std::vector<std::pair<double, v1::GasAlarm>> gas_alarms;  // run time t_s (as `events`) of each transition
  std::vector<geometry::Segment> walls;  // site map: walls and obstacle edges, world frame
  bool have_map = false;             // true: draw in the world frame with `walls`
  double start_x_m = 0, start_y_m = 0, start_theta_rad = 0;  // world pose of the odometry origin
  std::string map_name;
  double gas_inlet_x_m = 0, gas_inlet_y_m = 0;  // sensor inlet, robot frame (config gas.inlet_*); 0 = at the pose
};

struct RunReportResult {
  std::string dir;                // the report directory
  std::vector<std::string> pngs;  // paths of the PNGs drawn (report dir + file name)
  std::string summary_path;       // report dir + "/summary.md"
  /// One gas channel's leak-source estimate (world frame when have_map, else odometry frame).
  struct LeakResult {
    std::string channel;
    bool found = false;
    double x_m = 0, y_m = 0, radius95_m = 0;  // estimate and its 95 % circle (when found)
    double peak_x_m = 0, peak_y_m = 0;        // the concentration map's peak (lowest cell if falling)
    double max_value = 0, mean_value = 0;     // over the run's readings
    std::string unit, note;                   // note: why not found, or the estimate's caveats
  };
  std::vector<LeakResult> leaks;  // per gas channel with data, in channel order
};

/// Creates `report_dir` and writes trajectory.png, speed_people.png,
/// tracking_errors.png (when there is TRACKING telemetry), gas.png (when
/// there are gas values), gas_map_<name>.png per gas channel with data
/// (concentration map, path, walls, alarms, leak estimate; docs/gas-maps.md)
/// and summary.md. Without telemetry, or when gnuplot fails, only the
/// summary is written and says why. Throws std::runtime_error when the
/// directory or the summary cannot be written.
RunReportResult writeRunReport(const RunReportInput& in, const std::string& report_dir);

/// Indices of at most `max_points` of `n` samples, evenly strided, always
/// with the first and the last (decimation of long runs for plotting).
std::vector<std::size_t> sampleIndices(std::size_t n, std::size_t max_points);

}  // namespace inspect::server
