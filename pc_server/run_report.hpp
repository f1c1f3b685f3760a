#pragma once
// A recorded run's report: PNG plots (through the gnuplot helper) of the path,
// the speeds and people, the tracking errors and the gas channels, and a
// Markdown summary with the RunStats figures, the events and links to the
// plots and the run's files.
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "inspect/v1/link.pb.h"

namespace inspect::server {

struct RunReportInput {
  std::string run_id, robot, name, outcome, started_utc, ended_utc;
  std::vector<v1::Telemetry> telemetry;                  // in arrival order
  std::vector<std::pair<double, std::string>> events;   // t_s, text
  std::vector<std::string> files;                        // paths to link (made relative to the report)
};

struct RunReportResult {
  std::string dir;                // the report directory
  std::vector<std::string> pngs;  // paths of the PNGs drawn (report dir + file name)
  std::string summary_path;       // report dir + "/summary.md"
};

/// Creates `report_dir` and writes trajectory.png, speed_people.png,
/// tracking_errors.png (when there is TRACKING telemetry), gas.png (when
/// there are gas values) and summary.md. Without telemetry, or when gnuplot
/// fails, only the summary is written and says why. Throws
/// std::runtime_error when the directory or the summary cannot be written.
RunReportResult writeRunReport(const RunReportInput& in, const std::string& report_dir);

/// Indices of at most `max_points` of `n` samples, evenly strided, always
/// with the first and the last (decimation of long runs for plotting).
std::vector<std::size_t> sampleIndices(std::size_t n, std::size_t max_points);

}  // namespace inspect::server
