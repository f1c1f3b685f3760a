#pragma once
// The parts of a run report (run_report.cpp) that concern gas: the channels
// and their figures, the frame the maps are drawn in, the alarms from raise
// to clear and the summary's gas section (report_gas.cpp), and the gas maps
// with their leak-source estimates (gas_map_figures.cpp; docs/gas-maps.md).
// Internal to the report.
#include <cmath>
#include <limits>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "pc_server/recording/run_report.hpp"
#include "shared/gas/concentration_map.hpp"
#include "shared/gas/leak_estimator.hpp"

namespace inspect::server::report {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// Most points drawn per series.
constexpr std::size_t kMaxPoints = 5000;

/// A gas value in tables and labels ("%.4g").
std::string gasValue(double v);
/// One line of a Markdown table cell: no pipes, no line breaks.
std::string cell(std::string s);
/// "(x, y)" with two decimals, "-" when not finite.
std::string point(double x, double y);

// What the report knows of a gas channel: the robot's Hello, or a generic name.
struct Channel {
  int index = 0;
  std::string name, gas, unit;     // name "gas<i>" when unknown
  bool known = false;              // described by the robot's Hello
  double t90_s = 0, background = 0, alarm_low = kNaN, alarm_high = kNaN;
  bool falling = false;
  std::size_t samples = 0;         // finite readings
  double min = kNaN, max = kNaN, mean = kNaN;
  double tau_s() const { return t90_s > 0 ? t90_s / std::log(10.0) : 0.0; }
  std::string withUnit(const std::string& v) const { return unit.empty() ? v : v + " " + unit; }
};

/// Channel descriptions and NaN-free figures for every gas slot seen in the telemetry.
std::vector<Channel> gasChannels(const RunReportInput& in);

// The frame gas maps are drawn in: the site map's (world) when there is one,
// else odometry (origin and x axis = the robot's start pose).
struct Frame {
  bool world = false;
  double x0 = 0, y0 = 0, theta0 = 0;
  std::pair<double, double> point(double x, double y) const {
    const double c = std::cos(theta0), s = std::sin(theta0);
    return {x0 + c * x - s * y, y0 + s * x + c * y};
  }
  std::string name(const std::string& map_name) const {
    return world ? "world frame" + (map_name.empty() ? std::string() : " (map " + map_name + ")")
                 : "odometry frame (origin = start pose)";
  }
};

Frame reportFrame(const RunReportInput& in);
/// Seconds of telemetry message i from the first (robot clock).
double runTime(const std::vector<v1::Telemetry>& tel, std::size_t i);
/// One channel's readings where the sensor inlet was, in the report frame.
std::vector<gas::GasSample> gasSamples(const RunReportInput& in, const Frame& f, int channel);

// One gas alarm from raise to clear.
struct AlarmSpan {
  v1::GasAlarm raise;            // the raise (or the clear, when the raise was not recorded)
  double raised_t = kNaN;        // run time; NaN = raised before the recording
  double cleared_t = kNaN;       // NaN = still active at the end
  double peak = kNaN;
  double x = kNaN, y = kNaN;     // where it was raised, report frame
};

/// "A1 (low)", "A2 (high)", "sensor fault".
std::string levelName(v1::GasAlarm::Level l);
std::vector<AlarmSpan> alarmSpans(const RunReportInput& in, const Frame& f);

// The map, the estimate and the PNG of one channel.
struct GasMapOutcome {
  RunReportResult::LeakResult result;
  gas::LeakEstimate leak;
  gas::ConcentrationMap::Peak peak;
  std::string file;  // gas_map_<name>.png
};

struct PlotOutcome {
  std::vector<std::pair<std::string, std::string>> drawn;  // file name, description
  std::vector<std::string> notes;                          // what was not drawn and why
};

/// Draws gas_map_<name>.png for every channel with data (one shared extent:
/// the path, grown by 2 m, and the site map) and estimates each leak source.
std::vector<GasMapOutcome> gasMaps(const RunReportInput& in, const Frame& frame, const std::vector<Channel>& channels,
                                   const std::vector<AlarmSpan>& spans, const std::string& report_dir,
                                   RunReportResult& result, PlotOutcome& plots);

/// The summary's gas section: channels, alarms with durations and time in
/// alarm, and the leak-source estimates.
void writeGas(std::ostream& md, const RunReportInput& in, const Frame& frame, const std::vector<Channel>& channels,
              const std::vector<AlarmSpan>& spans, const std::vector<GasMapOutcome>& maps);

}  // namespace inspect::server::report
