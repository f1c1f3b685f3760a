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

#include "pc_server/recording/run_stats.hpp"
#include "pc_server/console/text_util.hpp"
#include "shared/gas/concentration_map.hpp"
#include "shared/gas/leak_estimator.hpp"
#include "shared/util/gnuplot.hpp"

namespace inspect::server {
namespace fs = std::filesystem;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::size_t kMaxPoints = 5000;  // per series
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
                                  [](const v1::Telemetry& t) { return t.v_m_s(); }));
  speed.series.push_back(overTime(s, {"commanded", {}, {}, "lines", "#ff7f0e", 2, true},
                                  [](const v1::Telemetry& t) { return t.cmd_v_m_s(); }));
  const bool anyone = std::any_of(s.msg.begin(), s.msg.end(), [](auto* t) { return t->nearest_person_m() >= 0; });
  plot::Panel people = panel(std::string("nearest person and the Eq 9 speed factor; zones: intimate < 0.45 m, "
                                         "personal < 1.2 m, social < 3.6 m") +
                                 (anyone ? "" : " (nobody seen)"),
                             "t (s)", "distance (m) / speed factor", "[0:*]");  // the zones start at 0
  people.bands = {{0.0, 0.45, "#f4b6b6", "intimate"}, {0.45, 1.2, "#fbe3b5", "personal"},
                  {1.2, 3.6, "#e3f0d5", "social"}};
  for (const auto& b : people.bands) people.labels.push_back({s.t_s.front(), (b.y0 + b.y1) / 2 - 0.08, b.label, "#555555"});
  if (anyone)
    people.series.push_back(overTime(s, {"nearest person distance (m)", {}, {}, "lines", "#d62728", 2, false},
                                     [](const v1::Telemetry& t) { return t.nearest_person_m() >= 0 ? t.nearest_person_m() : kNaN; }));
  people.series.push_back(overTime(s, {"speed factor (Eq 9)", {}, {}, "lines", "#1f77b4", 2, true},
                                   [](const v1::Telemetry& t) { return t.speed_factor(); }));
  return {speed, people};
}

std::vector<plot::Panel> trackingPanels(const Samples& s, const RunFigures& f) {
  auto onlyTracking = [](double (v1::Telemetry::*field)() const, double scale) {
    return [=](const v1::Telemetry& t) { return tracking(t) ? (t.*field)() * scale : kNaN; };
  };
  plot::Panel pos = panel("tracking position error (Eq 10), max " + fmtFixed(f.max_position_error_m, 3) +
                              " m, rms " + fmtFixed(f.rms_position_error_m, 3) + " m",
                          "t (s)", "position error (m)", "[0:*]", "off");
  pos.series.push_back(overTime(s, {"|(x_e, y_e)|", {}, {}, "lines", "#1f77b4", 2, false},
                                onlyTracking(&v1::Telemetry::position_error_m, 1.0)));
  plot::Panel ang = panel("tracking angle error, max " + fmtFixed(f.max_angle_error_rad * kRadToDeg, 1) + " deg",
                          "t (s)", "angle error (deg)", "[0:*]", "off");
  ang.series.push_back(overTime(s, {"|theta_e|", {}, {}, "lines", "#ff7f0e", 2, false},
                                onlyTracking(&v1::Telemetry::angle_error_rad, kRadToDeg)));
  return {pos, ang};
}

std::string gasValue(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

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

// Channel descriptions and NaN-free figures for every gas slot seen in the telemetry.
std::vector<Channel> gasChannels(const RunReportInput& in) {
  std::size_t n = in.gas_channels.size();
  for (const auto& t : in.telemetry) n = std::max(n, static_cast<std::size_t>(t.gas_size()));
  std::vector<Channel> out(n);
  std::vector<double> sums(n, 0.0);
  for (std::size_t c = 0; c < n; ++c) {
    Channel& ch = out[c];
    ch.index = static_cast<int>(c);
    ch.name = "gas" + std::to_string(c);
    if (c < in.gas_channels.size()) {
      const auto& g = in.gas_channels[c];
      ch.known = true;
      if (!g.name().empty()) ch.name = g.name();
      ch.gas = g.gas();
      ch.unit = g.unit();
      ch.t90_s = g.t90_s();
      ch.background = g.background();
      ch.falling = g.falling();
      if (g.alarm_low() != 0.0 || g.alarm_high() != 0.0) ch.alarm_low = g.alarm_low(), ch.alarm_high = g.alarm_high();
    }
  }
  for (const auto& t : in.telemetry)
    for (int c = 0; c < t.gas_size(); ++c) {
      const double v = t.gas(c);
      if (!std::isfinite(v)) continue;
      Channel& ch = out[static_cast<std::size_t>(c)];
      ch.min = ch.samples ? std::min(ch.min, v) : v;
      ch.max = ch.samples ? std::max(ch.max, v) : v;
      sums[static_cast<std::size_t>(c)] += v;
      ++ch.samples;
    }
  for (std::size_t c = 0; c < n; ++c)
    if (out[c].samples) out[c].mean = sums[c] / static_cast<double>(out[c].samples);
  return out;
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

// One line of a Markdown table cell: no pipes, no line breaks.
std::string cell(std::string s) {
  std::string out;
  for (char c : s) {
    if (c == '|') out += "\\|";
    else out += (c == '\n' || c == '\r') ? ' ' : c;
  }
  return out;
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

// ---- Gas maps (docs/gas-maps.md) ----

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

Frame reportFrame(const RunReportInput& in) {
  if (!in.have_map) return {};
  return {true, in.start_x_m, in.start_y_m, in.start_theta_rad};
}

double runTime(const std::vector<v1::Telemetry>& tel, std::size_t i) {
  return static_cast<double>(static_cast<int64_t>(tel[i].robot_time_us()) - static_cast<int64_t>(tel.front().robot_time_us())) * 1e-6;
}

// One channel's readings where the sensor inlet was, in the report frame.
std::vector<gas::GasSample> gasSamples(const RunReportInput& in, const Frame& f, int channel) {
  std::vector<gas::GasSample> out;
  for (std::size_t i = 0; i < in.telemetry.size(); ++i) {
    const auto& t = in.telemetry[i];
    if (channel >= t.gas_size() || !std::isfinite(t.gas(channel))) continue;
    const auto& p = t.pose();
    const double c = std::cos(p.theta_rad()), s = std::sin(p.theta_rad());
    const auto [x, y] = f.point(p.x_m() + c * in.gas_inlet_x_m - s * in.gas_inlet_y_m,
                                p.y_m() + s * in.gas_inlet_x_m + c * in.gas_inlet_y_m);
    out.push_back({runTime(in.telemetry, i), x, y, t.gas(channel)});
  }
  return out;
}

// One gas alarm from raise to clear.
struct AlarmSpan {
  v1::GasAlarm raise;            // the raise (or the clear, when the raise was not recorded)
  double raised_t = kNaN;        // run time; NaN = raised before the recording
  double cleared_t = kNaN;       // NaN = still active at the end
  double peak = kNaN;
  double x = kNaN, y = kNaN;     // where it was raised, report frame
};

std::string levelName(v1::GasAlarm::Level l) {
  switch (l) {
    case v1::GasAlarm::LOW: return "A1 (low)";
    case v1::GasAlarm::HIGH: return "A2 (high)";
    case v1::GasAlarm::SENSOR_FAULT: return "sensor fault";
    default: return "unspecified";
  }
}

std::vector<AlarmSpan> alarmSpans(const RunReportInput& in, const Frame& f) {
  std::vector<AlarmSpan> spans;
  auto where = [&](AlarmSpan& a, const v1::GasAlarm& g) {
    if (!g.has_pose()) return;
    std::tie(a.x, a.y) = f.point(g.pose().x_m(), g.pose().y_m());
  };
  for (const auto& tg : in.gas_alarms) {
    // Not a structured binding: clang 14 cannot capture one in the lambda below.
    const auto& t = tg.first;
    const auto& g = tg.second;
    if (g.active()) {
      AlarmSpan a;
      a.raise = g;
      a.raised_t = t;
      a.peak = g.peak();
      where(a, g);
      spans.push_back(std::move(a));
      continue;
    }
    auto open = std::find_if(spans.rbegin(), spans.rend(), [&](const AlarmSpan& a) {
      return a.raise.id() == g.id() && a.raise.channel() == g.channel() && std::isnan(a.cleared_t);
    });
    if (open != spans.rend()) {
      open->cleared_t = t;
      if (std::isfinite(g.peak())) open->peak = g.peak();
      continue;
    }
    AlarmSpan a;  // cleared, raised before the recording began
    a.raise = g;
    a.cleared_t = t;
    a.peak = g.peak();
    where(a, g);
    spans.push_back(std::move(a));
  }
  std::stable_sort(spans.begin(), spans.end(), [](const AlarmSpan& a, const AlarmSpan& b) {
    return (std::isnan(a.raised_t) ? -1.0 : a.raised_t) < (std::isnan(b.raised_t) ? -1.0 : b.raised_t);
  });
  return spans;
}

// Colours of the map: pale yellow (low) to dark red (high), as a gnuplot
// palette and interpolated here for the image's own RGBA pixels.
constexpr std::pair<double, unsigned> kMapStops[] = {
    {0.0, 0xffffd4}, {0.25, 0xfee391}, {0.5, 0xfe9929}, {0.75, 0xd7301f}, {1.0, 0x7f0000}};

unsigned mapColor(double frac) {
  frac = std::clamp(frac, 0.0, 1.0);
  for (std::size_t i = 1; i < std::size(kMapStops); ++i) {
    const auto [f1, c1] = kMapStops[i];
    const auto [f0, c0] = kMapStops[i - 1];
    if (frac > f1 && i + 1 < std::size(kMapStops)) continue;
    const double a = (frac - f0) / (f1 - f0);
    unsigned out = 0;
    for (int sh : {16, 8, 0}) {
      const double v0 = (c0 >> sh) & 0xff, v1 = (c1 >> sh) & 0xff;
      out |= static_cast<unsigned>(std::lround(v0 + a * (v1 - v0))) << sh;
    }
    return out;
  }
  return kMapStops[0].second;
}

// A gnuplot string literal ("\n" = a line break).
std::string gq(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (c == '\n') out += "\\n";
    else out += c;
  }
  return out + "\"";
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// Runs a gnuplot script kept next to the PNG; removes the script when it
// worked. Returns "" or what went wrong (as plot::renderPng).
std::string runGnuplot(const std::string& png_path, const std::string& script) {
  const std::string script_path = png_path + ".gp";
  {
    std::ofstream f(script_path);
    if (!(f << script)) return "cannot write " + script_path;
  }
  FILE* pipe = ::popen(("gnuplot " + gq(script_path) + " 2>&1").c_str(), "r");
  if (!pipe) return "cannot run gnuplot";
  std::string out;
  char buf[512];
  while (std::fgets(buf, sizeof buf, pipe)) out += buf;
  if (::pclose(pipe) != 0) return "gnuplot failed (is gnuplot-nox installed?): " + out.substr(0, 400);
  std::remove(script_path.c_str());
  return "";
}

// Everything one gas map shows.
struct GasMapFigure {
  const Channel* channel = nullptr;
  const gas::ConcentrationMap* map = nullptr;
  gas::LeakEstimate leak;
  gas::ConcentrationMap::Peak peak;
  std::vector<gas::GasSample> path;  // the samples (positions)
  std::vector<const AlarmSpan*> alarms;
  std::vector<RunReportInput::MapWall> walls;
  std::string frame_name;
};

bool crosses(double ax, double ay, double bx, double by, const RunReportInput::MapWall& w) {
  auto side = [](double ox, double oy, double px, double py, double qx, double qy) {
    return (px - ox) * (qy - oy) - (py - oy) * (qx - ox);
  };
  const double d1 = side(w.x0_m, w.y0_m, w.x1_m, w.y1_m, ax, ay), d2 = side(w.x0_m, w.y0_m, w.x1_m, w.y1_m, bx, by);
  const double d3 = side(ax, ay, bx, by, w.x0_m, w.y0_m), d4 = side(ax, ay, bx, by, w.x1_m, w.y1_m);
  return d1 * d2 < 0 && d3 * d4 < 0;
}

// Cells of the map whose nearest sampled point is behind a wall: the kernel
// does not know walls, so what it spreads through one is hidden.
std::vector<char> behindWalls(const gas::ConcentrationMap& m, const std::vector<gas::GasSample>& path,
                              const std::vector<RunReportInput::MapWall>& walls) {
  std::vector<char> hidden(m.cols() * m.rows(), 0);
  if (walls.empty()) return hidden;
  std::vector<std::pair<double, double>> pts;  // the path thinned to ~0.1 m
  for (const auto& p : path)
    if (pts.empty() || std::hypot(p.x_m - pts.back().first, p.y_m - pts.back().second) >= 0.1) pts.emplace_back(p.x_m, p.y_m);
  for (std::size_t r = 0; r < m.rows(); ++r)
    for (std::size_t c = 0; c < m.cols(); ++c) {
      if (!m.hasData(c, r)) continue;
      const double x = m.cellX(c), y = m.cellY(r);
      double best = std::numeric_limits<double>::infinity(), bx = x, by = y;
      for (const auto& [px, py] : pts)
        if (const double d = (px - x) * (px - x) + (py - y) * (py - y); d < best) best = d, bx = px, by = py;
      hidden[r * m.cols() + c] =
          std::any_of(walls.begin(), walls.end(), [&](const RunReportInput::MapWall& w) { return crosses(x, y, bx, by, w); });
    }
  return hidden;
}

std::string gasMapScript(const std::string& png_path, const GasMapFigure& f) {
  const Channel& ch = *f.channel;
  const gas::ConcentrationMap& m = *f.map;
  const gas::Bounds& b = m.bounds();
  // Colour range: the map's values, stretched to the warning threshold so that
  // readings below A1 never look alarming; falling channels run the other way.
  auto [lo, hi] = m.valueRange();
  if (ch.falling && std::isfinite(ch.alarm_low)) lo = std::min(lo, ch.alarm_low);
  if (!ch.falling && std::isfinite(ch.alarm_low)) hi = std::max(hi, ch.alarm_low);
  if (!std::isfinite(lo) || !std::isfinite(hi)) lo = 0.0, hi = 1.0;
  if (!(hi - lo > 1e-9)) hi = lo + 1.0;

  const std::vector<char> hidden = behindWalls(m, f.path, f.walls);
  std::ostringstream g;
  g.precision(7);
  g << "$img << EOD\n";
  for (std::size_t r = 0; r < m.rows(); ++r) {
    for (std::size_t c = 0; c < m.cols(); ++c) {
      const double v = m.value(c, r);
      unsigned rgb = 0xffffff, alpha = 0;
      if (std::isfinite(v) && !hidden[r * m.cols() + c]) {
        const double frac = (v - lo) / (hi - lo);
        rgb = mapColor(ch.falling ? 1.0 - frac : frac);
        alpha = static_cast<unsigned>(std::lround(70 + 185 * m.coverage(c, r)));  // faded where samples are few
      }
      g << num(m.cellX(c)) << ' ' << num(m.cellY(r)) << ' ' << (rgb >> 16) << ' ' << ((rgb >> 8) & 0xff) << ' '
        << (rgb & 0xff) << ' ' << alpha << '\n';
    }
    g << '\n';
  }
  g << "EOD\n$path << EOD\n";
  for (std::size_t i : sampleIndices(f.path.size(), kMaxPoints)) {
    if (i && std::hypot(f.path[i].x_m - f.path[i - 1].x_m, f.path[i].y_m - f.path[i - 1].y_m) > kMaxOdometryStepM) g << '\n';
    g << num(f.path[i].x_m) << ' ' << num(f.path[i].y_m) << '\n';
  }
  g << "EOD\n$walls << EOD\n";
  for (const auto& w : f.walls) g << num(w.x0_m) << ' ' << num(w.y0_m) << '\n' << num(w.x1_m) << ' ' << num(w.y1_m) << "\n\n";
  g << "EOD\n";
  const char* level_color[] = {"#999999", "#ff9f1c", "#e00000", "#8e44ad"};
  const char* label_color[] = {"#555555", "#8a4b00", "#a00000", "#5b2370"};  // darker: text on the map
  for (int lv = 1; lv <= 3; ++lv) {
    g << "$alarm" << lv << " << EOD\n";
    int labelled = 0;
    for (const AlarmSpan* a : f.alarms) {
      if (a->raise.level() != lv || !std::isfinite(a->x)) continue;
      std::string text = fmtShort(a->raised_t, 0) + " s";
      if (lv == v1::GasAlarm::SENSOR_FAULT) text += " " + a->raise.fault();
      else if (std::isfinite(a->raise.value())) text += " " + gasValue(a->raise.value());
      g << num(a->x) << ' ' << num(a->y) << ' ' << gq(++labelled <= 12 ? text : "") << '\n';
    }
    g << "EOD\n";
  }

  const int width_px = 1000;
  const double aspect = (b.y_max_m - b.y_min_m) / (b.x_max_m - b.x_min_m);
  const int height_px = static_cast<int>(std::clamp(760.0 * aspect + 230.0, 480.0, 1400.0));
  g << "set terminal pngcairo size " << width_px << "," << height_px << " font 'DejaVu Sans,10' noenhanced\n";
  g << "set encoding utf8\nset output " << gq(png_path) << "\n";
  const std::string what = ch.known ? ch.name + (ch.gas.empty() ? "" : " (" + ch.gas + ")") : ch.name;
  std::string title = what + " concentration" + (ch.unit.empty() ? "" : ", " + ch.unit) + " - " + f.frame_name + "\n";
  title += (ch.tau_s() > 0 ? "lag-compensated (t90 " + fmtShort(ch.t90_s, 1) + " s), " : "no lag compensation (t90 unknown), ");
  title += "Gaussian kernel 0.45 m; faded = few samples, hatched = no data\n";
  title += f.leak.found ? "leak source estimate (" + fmtFixed(f.leak.x_m, 2) + ", " + fmtFixed(f.leak.y_m, 2) + ") m \u00b1 " +
                              fmtShort(f.leak.radius95_m, 2) + " m (95 %)"
                        : "no leak source estimate: " + f.leak.reason;
  g << "set title " << gq(title) << "\n";
  g << "set xlabel 'x (m)'\nset ylabel 'y (m)'\n";
  g << "set size ratio -1\nset grid front lc rgb '#bbbbbb' lw 0.5\n";
  g << "set xrange [" << num(b.x_min_m) << ":" << num(b.x_max_m) << "]\n";
  g << "set yrange [" << num(b.y_min_m) << ":" << num(b.y_max_m) << "]\n";
  g << "set key outside bottom center horizontal maxrows 2 samplen 2\n";
  g << "set palette defined (";
  for (std::size_t k = 0; k < std::size(kMapStops); ++k) {  // falling: reversed, low = red
    const auto& stop = kMapStops[ch.falling ? std::size(kMapStops) - 1 - k : k];
    char col[16];
    std::snprintf(col, sizeof col, "#%06x", stop.second);
    g << (k ? ", " : "") << (ch.falling ? 1.0 - stop.first : stop.first) << " '" << col << "'";
  }
  g << ")\n";
  g << "set cbrange [" << num(lo) << ":" << num(hi) << "]\n";
  g << "set cblabel " << gq(ch.name + (ch.unit.empty() ? "" : " (" + ch.unit + ")")) << "\n";
  for (const auto& [name, th] : {std::pair{"A1", ch.alarm_low}, std::pair{"A2", ch.alarm_high}})
    if (std::isfinite(th) && th >= lo && th <= hi) g << "set cbtics add (" << gq(std::string(name) + " " + gasValue(th)) << " " << num(th) << ")\n";
  g << "set colorbox user origin graph 1.02, graph 0 size character 2, graph 1\nset rmargin 14\n";
  g << "set object 1 rectangle from graph 0, graph 0 to graph 1, graph 1 behind fc rgb '#b0b0b0' fs pattern 5 noborder\n";
  int label = 1;
  auto text = [&](double x, double y, const std::string& t, const std::string& color, const std::string& place) {
    g << "set label " << label++ << " " << gq(t) << " at " << num(x) << "," << num(y) << " " << place
      << " font ',9' tc rgb '" << color << "' boxed front\n";
  };
  g << "set style textbox opaque fc rgb '#33ffffff' noborder margins 1.5,1\n";  // labels stay legible on the map
  if (f.peak.valid)
    text(f.peak.x_m, f.peak.y_m, ch.withUnit(gasValue(f.peak.value)), "#000000", "left offset 1.2,-0.8");
  if (f.leak.found)  // under the circle, clear of the peak's label
    text(f.leak.x_m, f.leak.y_m - f.leak.radius95_m, "leak \u00b1" + fmtShort(f.leak.radius95_m, 2) + " m", "#0b3d91",
         "center offset 0,-0.9");

  auto block = [&](const std::string& name, const std::vector<std::pair<double, double>>& pts) {
    g << "$" << name << " << EOD\n";
    for (const auto& [x, y] : pts) g << num(x) << ' ' << num(y) << '\n';
    g << "EOD\n";
  };
  block("cbar", {{kNaN, kNaN}});
  if (!f.path.empty()) block("start", {{f.path.front().x_m, f.path.front().y_m}});
  if (f.peak.valid) block("peak", {{f.peak.x_m, f.peak.y_m}});
  if (f.leak.found) {
    block("leak", {{f.leak.x_m, f.leak.y_m}});
    std::vector<std::pair<double, double>> circle;
    for (int i = 0; i <= 96; ++i) {
      const double a = 2 * 3.14159265358979323846 * i / 96;
      circle.emplace_back(f.leak.x_m + f.leak.radius95_m * std::cos(a), f.leak.y_m + f.leak.radius95_m * std::sin(a));
    }
    block("circle", circle);
  }

  g << "plot $img using 1:2:3:4:5:6 with rgbalpha notitle";
  g << ", $cbar using 1:2:(" << num(lo) << ") with points pt 5 ps 0 lc palette notitle";  // makes the colour bar
  if (!f.walls.empty()) g << ", $walls using 1:2 with lines lw 3 lc rgb '#000000' title 'walls'";
  g << ", $path using 1:2 with lines lw 1.2 lc rgb '#3a3a3a' title 'path'";
  if (!f.path.empty()) g << ", $start using 1:2 with points pt 9 ps 1.8 lc rgb '#2ca02c' title 'start'";
  const char* level_title[] = {"", "alarm A1 raised", "alarm A2 raised", "sensor fault"};
  for (int lv = 1; lv <= 3; ++lv) {
    const bool any = std::any_of(f.alarms.begin(), f.alarms.end(),
                                 [&](const AlarmSpan* a) { return a->raise.level() == lv && std::isfinite(a->x); });
    if (!any) continue;
    g << ", $alarm" << lv << " using 1:2 with points pt 7 ps 1.5 lc rgb '" << level_color[lv] << "' title "
      << gq(level_title[lv]);
    g << ", $alarm" << lv << " using 1:2 with points pt 6 ps 1.5 lc rgb '#000000' notitle";
    g << ", $alarm" << lv << " using 1:2:3 with labels offset 0.8,0.8 left font ',8' tc rgb '" << label_color[lv]
      << "' boxed notitle";
  }
  if (f.peak.valid)
    g << ", $peak using 1:2 with points pt 12 ps 2.2 lw 2 lc rgb '#000000' title " << gq(ch.falling ? "map lowest" : "map peak");
  if (f.leak.found) {
    g << ", $leak using 1:2 with points pt 2 ps 2.5 lw 3 lc rgb '#0b3d91' title 'leak estimate'";
    g << ", $circle using 1:2 with lines lw 2 dt 2 lc rgb '#0b3d91' title '95 % region'";
  }
  g << "\n";
  return g.str();
}

// The map, the estimate and the PNG of one channel.
struct GasMapOutcome {
  RunReportResult::LeakResult result;
  gas::LeakEstimate leak;
  gas::ConcentrationMap::Peak peak;
  std::string file;  // gas_map_<name>.png
};

// A file-name-safe version of a channel name.
std::string fileSafe(const std::string& name) {
  std::string out;
  for (char c : name) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_') ? c : '_';
  return out.empty() ? "gas" : out;
}

struct PlotOutcome {
  std::vector<std::pair<std::string, std::string>> drawn;  // file name, description
  std::vector<std::string> notes;                          // what was not drawn and why
};

// Draws gas_map_<name>.png for every channel with data (one shared extent:
// the path, grown by 2 m, and the site map) and estimates each leak source.
std::vector<GasMapOutcome> gasMaps(const RunReportInput& in, const Frame& frame, const std::vector<Channel>& channels,
                                   const std::vector<AlarmSpan>& spans, const std::string& report_dir,
                                   RunReportResult& result, PlotOutcome& plots) {
  std::vector<GasMapOutcome> out;
  std::vector<std::vector<gas::GasSample>> samples(channels.size());
  constexpr double kInf = std::numeric_limits<double>::infinity();
  gas::Bounds bounds{kInf, kInf, -kInf, -kInf};
  auto grow = [&](double x0, double y0, double x1, double y1) {
    bounds = {std::min(bounds.x_min_m, x0), std::min(bounds.y_min_m, y0), std::max(bounds.x_max_m, x1),
              std::max(bounds.y_max_m, y1)};
  };
  for (const auto& ch : channels) {
    if (!ch.samples) continue;
    samples[static_cast<std::size_t>(ch.index)] = gasSamples(in, frame, ch.index);
    const gas::Bounds b = gas::boundsAround(samples[static_cast<std::size_t>(ch.index)], 2.0);
    if (b.valid()) grow(b.x_min_m, b.y_min_m, b.x_max_m, b.y_max_m);
  }
  std::vector<RunReportInput::MapWall> walls;
  gas::LeakOptions options;
  if (frame.world)
    for (const auto& w : in.walls) {
      if (!std::isfinite(w.x0_m + w.y0_m + w.x1_m + w.y1_m)) continue;
      walls.push_back(w);
      options.walls.push_back({w.x0_m, w.y0_m, w.x1_m, w.y1_m});
      grow(std::min(w.x0_m, w.x1_m) - 0.2, std::min(w.y0_m, w.y1_m) - 0.2, std::max(w.x0_m, w.x1_m) + 0.2,
           std::max(w.y0_m, w.y1_m) + 0.2);
    }
  if (!bounds.valid()) return out;
  gas::MapOptions map_options;
  map_options.max_cells = 250'000;  // a large site gets coarser cells, not a huge PNG script

  for (const auto& ch : channels) {
    if (!ch.samples) continue;
    const auto& raw = samples[static_cast<std::size_t>(ch.index)];
    GasMapOutcome o;
    const auto map = gas::ConcentrationMap::build(gas::compensateLag(raw, ch.tau_s()), bounds, map_options);
    options.falling = ch.falling;
    // A leak worth locating raised the channel to its A1 level at least once;
    // below it the "plume" is noise, cross-sensitivity or a stuck sensor.
    // With the robot's alarm events in the run: an A1 or A2 alarm raised on
    // the channel (filtered, minimum duration: not a noise spike, not a stuck
    // reading). Without any (older runs): the readings' extreme.
    bool any_alarms = false, raised = false;
    for (const auto& [t, a] : in.gas_alarms) {
      any_alarms = true;
      raised |= static_cast<int>(a.channel()) == ch.index && a.active() &&
                (a.level() == v1::GasAlarm::LOW || a.level() == v1::GasAlarm::HIGH);
    }
    const bool reached_a1 = !ch.known || std::isnan(ch.alarm_low) ||
                            (any_alarms ? raised : (ch.falling ? ch.min <= ch.alarm_low : ch.max >= ch.alarm_low));
    if (reached_a1) {
      o.leak = gas::estimateLeak(raw, ch.tau_s(), ch.background, bounds, options);
    } else {
      o.leak.found = false;
      o.leak.reason = "the readings never reached A1 (" +
                      ch.withUnit(gasValue(ch.falling ? ch.min : ch.max)) + (ch.falling ? " > " : " < ") +
                      ch.withUnit(gasValue(ch.alarm_low)) + ")";
    }
    o.peak = map.peak(ch.falling);
    auto& r = o.result;
    r.channel = ch.name;
    r.found = o.leak.found;
    if (r.found) r.x_m = o.leak.x_m, r.y_m = o.leak.y_m, r.radius95_m = o.leak.radius95_m;
    r.peak_x_m = o.peak.valid ? o.peak.x_m : kNaN;
    r.peak_y_m = o.peak.valid ? o.peak.y_m : kNaN;
    r.max_value = ch.max;
    r.mean_value = ch.mean;
    r.unit = ch.unit;
    r.note = o.leak.reason;
    if (ch.tau_s() <= 0.0)
      r.note += std::string(r.note.empty() ? "" : "; ") + "sensor response time unknown: its lag is not undone";

    o.file = "gas_map_" + fileSafe(ch.name) + ".png";
    GasMapFigure fig;
    fig.channel = &ch;
    fig.map = &map;
    fig.leak = o.leak;
    fig.peak = o.peak;
    fig.path = raw;
    fig.walls = walls;
    fig.frame_name = frame.name(in.map_name);
    for (const auto& a : spans)
      if (static_cast<int>(a.raise.channel()) == ch.index && std::isfinite(a.raised_t)) fig.alarms.push_back(&a);
    const std::string path = (fs::path(report_dir) / o.file).string();
    const std::string err = runGnuplot(path, gasMapScript(path, fig));
    std::error_code ec;
    if (err.empty()) {
      result.pngs.push_back(path);
      plots.drawn.emplace_back(o.file, ch.name + " concentration map (" + (ch.tau_s() > 0 ? "lag-compensated, " : "") +
                                           "kernel 0.45 m) with the path, " + (walls.empty() ? "" : "walls, ") +
                                           "alarm raise points, the map's peak and the leak estimate with its 95 % circle");
    } else {
      fs::remove(path + ".gp", ec);
      fs::remove(path, ec);
      plots.notes.push_back(o.file + " not drawn: " + err);
    }
    result.leaks.push_back(r);
    out.push_back(std::move(o));
  }
  return out;
}

std::string point(double x, double y) {
  return std::isfinite(x) && std::isfinite(y) ? "(" + fmtFixed(x, 2) + ", " + fmtFixed(y, 2) + ")" : "-";
}

// The summary's gas section: channels, alarms with durations and time in
// alarm, and the leak-source estimates.
void writeGas(std::ostream& md, const RunReportInput& in, const Frame& frame, const std::vector<Channel>& channels,
              const std::vector<AlarmSpan>& spans, const std::vector<GasMapOutcome>& maps) {
  const bool any = std::any_of(channels.begin(), channels.end(), [](const Channel& c) { return c.samples > 0; });
  if (!any && spans.empty() && in.gas_channels.empty()) return;
  md << "## Gas\n\n";
  const std::string where = frame.name(in.map_name);
  if (any) {
    md << "| channel | gas | readings | min | max | mean | map peak at (m) | leak source (m, 95 %) |\n"
          "| --- | --- | --- | --- | --- | --- | --- | --- |\n";
    std::size_t k = 0;
    for (const auto& ch : channels) {
      if (!ch.samples) continue;
      const GasMapOutcome* m = k < maps.size() && maps[k].result.channel == ch.name ? &maps[k++] : nullptr;
      md << "| " << cell(ch.name) << " | " << (ch.gas.empty() ? "-" : cell(ch.gas)) << " | " << ch.samples << " | " << ch.withUnit(gasValue(ch.min))
         << " | " << ch.withUnit(gasValue(ch.max)) << " | " << ch.withUnit(gasValue(ch.mean)) << " | ";
      if (m && m->peak.valid) md << point(m->peak.x_m, m->peak.y_m) << " " << ch.withUnit(gasValue(m->peak.value));
      else md << "-";
      md << " | ";
      if (m && m->leak.found) md << point(m->leak.x_m, m->leak.y_m) << " +- " << fmtFixed(m->leak.radius95_m, 2);
      else md << "not found";
      md << " |\n";
    }
    md << "\nPositions are in the " << where << "; the map peak is the highest cell of the lag-compensated map"
       << " (lowest for falling channels such as O2).\n\n";
  }

  const double end_t = in.telemetry.empty() ? (in.gas_alarms.empty() ? 0.0 : in.gas_alarms.back().first)
                                            : runTime(in.telemetry, in.telemetry.size() - 1);
  auto nameOf = [&](const v1::GasAlarm& a) {
    if (!a.channel_name().empty()) return a.channel_name();
    return a.channel() < channels.size() ? channels[a.channel()].name : "gas" + std::to_string(a.channel());
  };
  md << "### Gas alarms\n\n";
  if (spans.empty()) md << "No gas alarms.\n\n";
  else {
    md << "| raised (s) | cleared (s) | duration | channel | level | value at raise | threshold | peak | raised at (m) |\n"
          "| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
    for (const auto& a : spans) {
      const auto& g = a.raise;
      const std::string unit = g.unit().empty() && g.channel() < channels.size() ? channels[g.channel()].unit : g.unit();
      auto withUnit = [&](double v) { return std::isfinite(v) ? gasValue(v) + (unit.empty() ? "" : " " + unit) : "-"; };
      std::string duration;
      if (std::isnan(a.raised_t)) duration = "raised before the recording";
      else if (std::isnan(a.cleared_t)) duration = "still active at end (" + fmtFixed(end_t - a.raised_t, 1) + " s so far)";
      else duration = fmtFixed(a.cleared_t - a.raised_t, 1) + " s";
      std::string level = levelName(g.level());
      if (g.level() == v1::GasAlarm::SENSOR_FAULT && !g.fault().empty()) level += ": " + g.fault();
      md << "| " << (std::isnan(a.raised_t) ? "-" : fmtFixed(a.raised_t, 1)) << " | "
         << (std::isnan(a.cleared_t) ? "-" : fmtFixed(a.cleared_t, 1)) << " | " << duration << " | " << cell(nameOf(g))
         << " | " << cell(level) << " | " << (g.active() ? withUnit(g.value()) : "-") << " | "
         << (g.level() == v1::GasAlarm::SENSOR_FAULT ? "-" : withUnit(g.threshold())) << " | " << withUnit(a.peak) << " | "
         << (g.active() ? point(a.x, a.y) : "-") << " |\n";
    }
    md << "\n";
    // Time in alarm per channel and level (open alarms count to the end of the run).
    std::vector<std::tuple<std::string, int, int, double, bool>> totals;  // channel, level, count, seconds, open
    for (const auto& a : spans) {
      const std::string ch = nameOf(a.raise);
      const int lv = a.raise.level();
      auto it = std::find_if(totals.begin(), totals.end(), [&](const auto& t) { return std::get<0>(t) == ch && std::get<1>(t) == lv; });
      if (it == totals.end()) it = totals.insert(totals.end(), {ch, lv, 0, 0.0, false});
      const double t0 = std::isnan(a.raised_t) ? 0.0 : a.raised_t, t1 = std::isnan(a.cleared_t) ? end_t : a.cleared_t;
      std::get<2>(*it) += 1;
      std::get<3>(*it) += std::max(0.0, t1 - t0);
      std::get<4>(*it) = std::get<4>(*it) || std::isnan(a.cleared_t);
    }
    std::sort(totals.begin(), totals.end(), [](const auto& a, const auto& b) {
      return std::tie(std::get<0>(a), std::get<1>(a)) < std::tie(std::get<0>(b), std::get<1>(b));
    });
    md << "Time in alarm (an alarm still active counts to the end of the run, " << fmtFixed(end_t, 1) << " s):\n\n"
       << "| channel | level | alarms | total time |\n| --- | --- | --- | --- |\n";
    for (const auto& [ch, lv, count, secs, open] : totals)
      md << "| " << cell(ch) << " | " << levelName(static_cast<v1::GasAlarm::Level>(lv)) << " | " << count << " | "
         << fmtFixed(secs, 1) << " s" << (open ? " (still active at end)" : "") << " |\n";
    md << "\n";
  }

  if (!maps.empty()) {
    md << "### Leak-source estimates\n\n";
    for (const auto& m : maps) {
      const auto& e = m.leak;
      const auto& r = m.result;
      md << "- **" << r.channel << "**: ";
      if (e.found) {
        md << "leak source at " << point(e.x_m, e.y_m) << " m +- " << fmtFixed(e.radius95_m, 2)
           << " m (95 %), " << where << "; plume length scale " << fmtShort(e.length_m, 2)
           << " m, modelled peak " << gasValue(e.peak_signal) << (r.unit.empty() ? "" : " " + r.unit)
           << " above background at " << (e.snr < 1000 ? fmtShort(e.snr, 0) + " x" : "over 1000 x") << " the sensor noise";
        if (!r.note.empty()) md << ". Note: " << r.note;
      } else {
        md << "no source estimate: " << r.note;
      }
      md << ".\n";
    }
    md << "\nThe estimate fits a peaked plume, seen through the sensor's lag along the recorded path, to the raw "
          "readings; the circle holds 95 % of the resulting probability (docs/gas-maps.md).\n\n";
  }
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
