#include "pc_server/recording/run_report.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "pc_server/recording/report_gas.hpp"
#include "pc_server/recording/run_stats.hpp"
#include "shared/util/number_text.hpp"
#include "shared/util/gnuplot.hpp"

namespace inspect::server {

using util::fmtFixed;
using util::fmtShort;
namespace fs = std::filesystem;

namespace {

using namespace report;
constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;
const char* const kGasColor[] = {"#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#bcbd22"};

// The decimated telemetry with its time (s from the first message, robot
// clock) and the distance travelled up to it.
struct Samples {
  std::vector<const v1::Telemetry*> msg;
  std::vector<double> t_s, dist_m;
  std::size_t size() const { return msg.size(); }
};

Samples sampleTelemetry(const std::vector<v1::Telemetry>& tel) {
  std::vector<double> dist(tel.size(), 0.0);
  for (std::size_t i = 1; i < tel.size(); ++i) {
    const double step = std::hypot(tel[i].pose().x_m() - tel[i - 1].pose().x_m(),
                                   tel[i].pose().y_m() - tel[i - 1].pose().y_m());
    dist[i] = dist[i - 1] + (step < kMaxOdometryStepM ? step : 0.0);
  }
  Samples s;
  const auto t0 = static_cast<int64_t>(tel.empty() ? 0 : tel.front().robot_time_us());
  for (std::size_t i : sampleIndices(tel.size(), kMaxPoints)) {
    s.msg.push_back(&tel[i]);
    s.t_s.push_back(static_cast<double>(static_cast<int64_t>(tel[i].robot_time_us()) - t0) * 1e-6);
    s.dist_m.push_back(dist[i]);
  }
  return s;
}

// A series of n points (fx(i), fy(i)); NaN makes a gap.
template <class FX, class FY>
plot::Series trace(plot::Series s, std::size_t n, FX fx, FY fy) {
  for (std::size_t i = 0; i < n; ++i) {
    s.x.push_back(fx(i));
    s.y.push_back(fy(i));
  }
  return s;
}

// A series over time from a telemetry field.
template <class F>
plot::Series overTime(const Samples& s, plot::Series base, F field) {
  return trace(std::move(base), s.size(), [&](std::size_t i) { return s.t_s[i]; },
               [&](std::size_t i) { return field(*s.msg[i]); });
}

// Panels over time keep their legend above the graph, clear of the data.
plot::Panel panel(std::string title, std::string xlabel, std::string ylabel, std::string yrange = "",
                  std::string key = "tmargin center horizontal") {
  plot::Panel p;
  p.key = std::move(key);
  p.title = std::move(title);
  p.xlabel = std::move(xlabel);
  p.ylabel = std::move(ylabel);
  p.yrange = std::move(yrange);
  return p;
}

bool tracking(const v1::Telemetry& t) { return t.mode() == v1::TRACKING; }

// A round step giving at most ~10 time marks over the run.
double markStep(double duration_s) {
  for (double step : {1.0, 2.0, 5.0, 10.0, 20.0, 30.0, 60.0, 120.0, 300.0, 600.0, 1800.0})
    if (duration_s / step <= 10.0) return step;
  return 3600.0;
}

plot::Panel trajectoryPanel(const RunReportInput& in, const Samples& s, bool any_tracking) {
  const std::string who = in.name.empty() ? in.run_id : in.name;
  plot::Panel p = panel(who + ": path (odometry), time marks in s", "x (m)", "y (m)");
  p.equal_axes = true;
  p.key = "outside right";
  p.series.push_back(trace(plot::Series{"robot", {}, {}, "lines", "#1f77b4", 2, false}, s.size(),
                           [&](std::size_t i) { return s.msg[i]->pose().x_m(); },
                           [&](std::size_t i) { return s.msg[i]->pose().y_m(); }));
  if (any_tracking)
    p.series.push_back(trace(plot::Series{"tracking reference", {}, {}, "lines", "#7f7f7f", 2, true}, s.size(),
                             [&](std::size_t i) { return tracking(*s.msg[i]) ? s.msg[i]->reference().x_m() : kNaN; },
                             [&](std::size_t i) { return tracking(*s.msg[i]) ? s.msg[i]->reference().y_m() : kNaN; }));
  const double step = markStep(s.t_s.back());
  plot::Series marks{"", {}, {}, "points pt 7 ps 0.5", "#1f77b4", 1, false};
  for (std::size_t i = 0, k = 1; i < s.size(); ++i)
    if (s.t_s[i] >= static_cast<double>(k) * step) {
      const auto& pose = s.msg[i]->pose();
      marks.x.push_back(pose.x_m());
      marks.y.push_back(pose.y_m());
      p.labels.push_back({pose.x_m(), pose.y_m(), fmtShort(static_cast<double>(k) * step, 0), "#1f77b4"});
      k = static_cast<std::size_t>(std::floor(s.t_s[i] / step)) + 1;
    }
  p.series.push_back(std::move(marks));
  const auto& a = s.msg.front()->pose();
  const auto& b = s.msg.back()->pose();
  p.series.push_back({"start", {a.x_m()}, {a.y_m()}, "points pt 9 ps 2", "#2ca02c", 1, false});
  p.series.push_back({"end", {b.x_m()}, {b.y_m()}, "points pt 5 ps 1.6", "#d62728", 1, false});
  return p;
}

std::vector<plot::Panel> speedPeoplePanels(const Samples& s) {
  plot::Panel speed = panel("robot speed", "t (s)", "v (m/s)");
  speed.series.push_back(overTime(s, {"measured", {}, {}, "lines", "#1f77b4", 2, false},
                                  [](const v1::Telemetry& t) { return t.has_v_m_s() ? t.v_m_s() : kNaN; }));
  speed.series.push_back(overTime(s, {"commanded", {}, {}, "lines", "#ff7f0e", 2, true},
                                  [](const v1::Telemetry& t) { return t.has_cmd_v_m_s() ? t.cmd_v_m_s() : kNaN; }));
  const bool anyone = std::any_of(s.msg.begin(), s.msg.end(), [](auto* t) { return t->has_nearest_person_m() && t->nearest_person_m() >= 0; });
  plot::Panel people = panel(std::string("nearest person and the Eq 9 speed factor; zones: intimate < 0.45 m, "
                                         "personal < 1.2 m, social < 3.6 m") +
                                 (anyone ? "" : " (nobody seen)"),
                             "t (s)", "distance (m) / speed factor", "[0:*]");  // the zones start at 0
  people.bands = {{0.0, 0.45, "#f4b6b6", "intimate"}, {0.45, 1.2, "#fbe3b5", "personal"},
                  {1.2, 3.6, "#e3f0d5", "social"}};
  for (const auto& b : people.bands) people.labels.push_back({s.t_s.front(), (b.y0 + b.y1) / 2 - 0.08, b.label, "#555555"});
  if (anyone)
    people.series.push_back(overTime(s, {"nearest person distance (m)", {}, {}, "lines", "#d62728", 2, false},
                                     [](const v1::Telemetry& t) {
                                       return t.has_nearest_person_m() && t.nearest_person_m() >= 0 ? t.nearest_person_m() : kNaN;
                                     }));
  people.series.push_back(overTime(s, {"speed factor (Eq 9)", {}, {}, "lines", "#1f77b4", 2, true},
                                   [](const v1::Telemetry& t) { return t.has_speed_factor() ? t.speed_factor() : kNaN; }));
  return {speed, people};
}

std::vector<plot::Panel> trackingPanels(const Samples& s, const RunFigures& f) {
  // Unknown (left out, link protocol 2) is no sample, like not tracking.
  auto onlyTracking = [](bool (v1::Telemetry::*has)() const, double (v1::Telemetry::*field)() const, double scale) {
    return [=](const v1::Telemetry& t) { return tracking(t) && (t.*has)() ? (t.*field)() * scale : kNaN; };
  };
  plot::Panel pos = panel("tracking position error (Eq 10), max " + fmtFixed(f.max_position_error_m, 3) +
                              " m, rms " + fmtFixed(f.rms_position_error_m, 3) + " m",
                          "t (s)", "position error (m)", "[0:*]", "off");
  pos.series.push_back(overTime(s, {"|(x_e, y_e)|", {}, {}, "lines", "#1f77b4", 2, false},
                                onlyTracking(&v1::Telemetry::has_position_error_m, &v1::Telemetry::position_error_m, 1.0)));
  plot::Panel ang = panel("tracking angle error, max " + fmtFixed(f.max_angle_error_rad * kRadToDeg, 1) + " deg",
                          "t (s)", "angle error (deg)", "[0:*]", "off");
  ang.series.push_back(overTime(s, {"|theta_e|", {}, {}, "lines", "#ff7f0e", 2, false},
                                onlyTracking(&v1::Telemetry::has_angle_error_rad, &v1::Telemetry::angle_error_rad, kRadToDeg)));
  return {pos, ang};
}


// One panel per channel over time (each on its own scale, with its alarm
// thresholds), then all channels along the path, each scaled to its own range.
std::vector<plot::Panel> gasPanels(const Samples& s, const std::vector<Channel>& channels) {
  std::vector<plot::Panel> panels;
  plot::Panel along = panel("gas along the path, each channel scaled to its range (0 = its min, 1 = its max)",
                            "distance travelled (m)", "relative concentration", "[-0.05:1.05]");
  for (const auto& g : channels) {
    if (!g.samples) continue;
    const int c = g.index;
    auto value = [&](std::size_t i) { return c < s.msg[i]->gas_size() ? s.msg[i]->gas(c) : kNaN; };
    const double range = g.max > g.min ? g.max - g.min : 1.0;
    const std::string color = kGasColor[c % std::size(kGasColor)];
    const plot::Series base{g.known ? g.name : "channel " + std::to_string(c), {}, {}, "lines", color, 2, false};
    const std::string what = g.known ? g.name + (g.gas.empty() ? "" : " (" + g.gas + ")") : "gas channel " + std::to_string(c);
    plot::Panel p = panel(what + " over time: max " + g.withUnit(gasValue(g.max)) + ", mean " + g.withUnit(gasValue(g.mean)) +
                              (g.falling ? ", min " + g.withUnit(gasValue(g.min)) : ""),
                          "t (s)", g.known && !g.unit.empty() ? g.name + " (" + g.unit + ")" : "concentration (channel units)",
                          "", "off");
    p.series.push_back(trace(base, s.size(), [&](std::size_t i) { return s.t_s[i]; }, value));
    // Thresholds within reach of the data are drawn; far-off ones would flatten the trace.
    for (const auto& [level, th, col] : {std::tuple{"A1", g.alarm_low, "#ff7f0e"}, std::tuple{"A2", g.alarm_high, "#d62728"}})
      if (std::isfinite(th) && th >= g.min - range && th <= g.max + range) {
        p.series.push_back({"", {s.t_s.front(), s.t_s.back()}, {th, th}, "lines", col, 1, true});
        p.labels.push_back({s.t_s.front(), th, std::string(level) + " " + gasValue(th), col});
      }
    panels.push_back(std::move(p));
    along.series.push_back(trace(base, s.size(), [&](std::size_t i) { return s.dist_m[i]; },
                                 [&](std::size_t i) { return (value(i) - g.min) / range; }));
  }
  panels.push_back(std::move(along));
  return panels;
}


// A file's link target relative to the report directory (absolute if that fails).
std::string linkTarget(const std::string& file, const fs::path& report_dir) {
  std::error_code ec;
  const fs::path abs = fs::absolute(file, ec);
  if (ec) return file;
  const fs::path rel = abs.lexically_normal().lexically_relative(fs::absolute(report_dir, ec).lexically_normal());
  const std::string target = rel.empty() ? abs.string() : rel.string();
  return target.find_first_of(" ()") == std::string::npos ? target : "<" + target + ">";
}

void writeFigures(std::ostream& md, const RunFigures& f, const std::vector<Channel>& channels) {
  md << "## Figures\n\n| figure | value |\n| --- | --- |\n";
  md << "| telemetry messages | " << f.telemetry << " |\n";
  md << "| duration | " << fmtFixed(f.duration_s, 1) << " s |\n";
  md << "| distance travelled | " << fmtFixed(f.distance_m, 2) << " m |\n";
  md << "| min distance to people | " << (f.min_person_m < 0 ? "nobody seen" : fmtFixed(f.min_person_m, 2) + " m")
     << " |\n";
  md << "| tracking samples | " << f.tracking_samples << " |\n";
  if (f.tracking_samples) {
    md << "| tracking max position error | " << fmtFixed(f.max_position_error_m, 3) << " m |\n";
    md << "| tracking rms position error | " << fmtFixed(f.rms_position_error_m, 3) << " m |\n";
    md << "| tracking max angle error | " << fmtFixed(f.max_angle_error_rad, 3) << " rad ("
       << fmtFixed(f.max_angle_error_rad * kRadToDeg, 1) << " deg) |\n";
  }
  for (const auto& g : channels) {
    if (!g.samples) continue;
    const std::string who = g.known ? g.name : "channel " + std::to_string(g.index);
    if (g.falling) md << "| gas " << who << " min | " << g.withUnit(gasValue(g.min)) << " |\n";
    md << "| gas " << who << " max | " << g.withUnit(gasValue(g.max)) << " |\n";
    md << "| gas " << who << " mean | " << g.withUnit(gasValue(g.mean)) << " |\n";
  }
  md << "\n";
}




}  // namespace

std::vector<std::size_t> sampleIndices(std::size_t n, std::size_t max_points) {
  std::vector<std::size_t> idx;
  if (n == 0 || max_points == 0) return idx;
  if (n <= max_points) {
    for (std::size_t i = 0; i < n; ++i) idx.push_back(i);
    return idx;
  }
  if (max_points < 3) return max_points == 1 ? std::vector<std::size_t>{0} : std::vector<std::size_t>{0, n - 1};
  const std::size_t stride = (n - 1 + max_points - 3) / (max_points - 2);  // ceil((n-1)/(max-2))
  for (std::size_t i = 0; i < n; i += stride) idx.push_back(i);
  if (idx.back() != n - 1) idx.push_back(n - 1);
  return idx;
}

RunReportResult writeRunReport(const RunReportInput& in, const std::string& report_dir) {
  RunReportResult result;
  result.dir = report_dir;
  std::error_code ec;
  fs::create_directories(report_dir, ec);
  if (ec) throw std::runtime_error("cannot create " + report_dir + ": " + ec.message());

  RunStats stats;
  for (const auto& t : in.telemetry) stats.add(t);
  const RunFigures figures = stats.figures();
  const std::vector<Channel> channels = gasChannels(in);
  const bool any_gas = std::any_of(channels.begin(), channels.end(), [](const Channel& c) { return c.samples > 0; });
  const Frame frame = reportFrame(in);
  const std::vector<AlarmSpan> spans = alarmSpans(in, frame);
  std::vector<GasMapOutcome> gas_maps;

  PlotOutcome plots;
  if (!in.telemetry.empty()) {
    const Samples s = sampleTelemetry(in.telemetry);
    auto draw = [&](const std::string& file, const std::vector<plot::Panel>& panels, const std::string& what,
                    int panel_height_px = 420) {
      const std::string path = (fs::path(report_dir) / file).string();
      const std::string err = plot::renderPng(path, panels, 1000, panel_height_px);
      if (err.empty()) {
        result.pngs.push_back(path);
        plots.drawn.emplace_back(file, what);
        return;
      }
      fs::remove(path + ".gp", ec);  // the helper keeps its script on failure
      fs::remove(path, ec);
      plots.notes.push_back(file + " not drawn: " + err);
    };
    draw("trajectory.png", {trajectoryPanel(in, s, figures.tracking_samples > 0)},
         "the robot's path (odometry) with the tracking reference, start and end marked", 640);
    draw("speed_people.png", speedPeoplePanels(s),
         "measured and commanded speed; nearest person distance over the proxemic zones, with the Eq 9 speed factor");
    if (figures.tracking_samples)
      draw("tracking_errors.png", trackingPanels(s, figures), "tracking position and angle errors over time");
    else
      plots.notes.push_back("tracking_errors.png not drawn: no TRACKING telemetry in this run");
    if (any_gas)
      draw("gas.png", gasPanels(s, channels), "each gas channel over time, and all along the path", 320);
    else
      plots.notes.push_back("gas.png not drawn: no gas values in the telemetry");
    gas_maps = gasMaps(in, frame, channels, spans, report_dir, result, plots);
  }

  std::ostringstream md;
  md << "# Run report: " << (in.name.empty() ? in.run_id : in.name) << "\n\n";
  md << "- Run id: " << in.run_id << "\n- Robot: " << in.robot << "\n- Name: " << in.name
     << "\n- Started (UTC): " << in.started_utc << "\n- Ended (UTC): " << in.ended_utc
     << "\n- Outcome: " << in.outcome << "\n\n";
  if (in.telemetry.empty())
    md << "There was no telemetry in this run: no figures and no plots.\n\n";
  else
    writeFigures(md, figures, channels);

  md << "## Events\n\n";
  if (in.events.empty()) md << "No events.\n\n";
  else {
    md << "| t (s) | event |\n| --- | --- |\n";
    for (const auto& [t, text] : in.events) md << "| " << fmtFixed(t, 1) << " | " << cell(text) << " |\n";
    md << "\n";
  }

  writeGas(md, in, frame, channels, spans, gas_maps);

  if (!in.telemetry.empty()) {
    md << "## Plots\n\n";
    if (plots.drawn.empty()) md << "No plots were drawn.\n\n";
    for (const auto& [file, what] : plots.drawn) md << "- [" << file << "](" << file << "): " << what << "\n";
    for (const auto& n : plots.notes) md << "- " << n << "\n";
    md << "\n";
    for (const auto& [file, what] : plots.drawn) md << "![" << file << "](" << file << ")\n\n";
  }

  md << "## Files\n\n";
  if (in.files.empty()) md << "No files.\n";
  for (const auto& f : in.files)
    md << "- [" << fs::path(f).filename().string() << "](" << linkTarget(f, report_dir) << ")\n";

  result.summary_path = (fs::path(report_dir) / "summary.md").string();
  std::ofstream out(result.summary_path);
  out << md.str();
  if (!out.flush()) throw std::runtime_error("cannot write " + result.summary_path);
  return result;
}

}  // namespace inspect::server
