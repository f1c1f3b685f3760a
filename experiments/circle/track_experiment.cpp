// track_experiment: the paper's trajectory-tracking experiment (section 5.2,
// Figs 18 and 20, Table 3) run in-process, far faster than real time: the
// tracker the robot runs (Eqs 10-15) with PID and fuzzy-PID wheel loops
// against the simulator's plant and the MCU's noise model
// (sim/closed_loop.hpp). Prints the set-up, a metrics table next to the
// paper's figures and the speed of the run; optionally writes JSON and PNG
// plots. scripts/reproduce_circle.sh is the one-command front end;
// docs/controllers.md explains the definitions.
#include <algorithm>
#include <array>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shared/config/control_config.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/control/reference_path.hpp"
#include "shared/util/gnuplot.hpp"
#include "sim/closed_loop.hpp"

namespace {

using namespace inspect;
using control::WheelControl;
using Clock = std::chrono::steady_clock;
using plot::panel;
using plot::series;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

constexpr const char* kUsage = R"(usage: track_experiment [options]
The paper's circle-tracking experiment (Figs 18, 20): the same tracker
(Eqs 10-13) with a PID (Eq 14) or fuzzy-PID (Eqs 14-15) wheel loop against
the simulated robot, compared metric by metric with the paper.
  --trajectory circle|line|waypoints   reference (default circle)
  --radius M        circle radius, m; < 0 turns clockwise (default 3.5)
  --speed M_S       reference speed, m/s (default 0.5; the paper does not say)
  --laps N          circle laps (default 1)
  --length M        line length; waypoints: a length x length/2 rectangle (default 10)
  --controllers L   comma list of pid, fuzzy_pid, direct (default pid,fuzzy_pid)
  --robot FILE      robot config (default config/robot.yaml)
  --control FILE    control config (default config/control.yaml)
  --seed N          noise seed (default 1)
  --seeds K         repeat over seeds N..N+K-1, report mean / max (default 1)
  --no-noise        exact wheel-speed and heading measurements
  --band-m M        position convergence band, m (default 0.01)
  --band-rad R      angle convergence band, rad (default 0.01)
  --plots DIR       write Fig 18 / Fig 20 / wheel-and-gain PNGs into DIR
  --json FILE       write the figures as JSON
  --help            this text
Exit status: 0 done, 1 a plot or the JSON could not be written, 2 bad arguments or config.
)";

constexpr const char* kConvergenceDefinition =
    "convergence time = the first control tick after the LAST tick whose error exceeded the band, i.e. the "
    "time after which the error stays within the band until the end of the run (0 if it never left the band; "
    "'not conv.' if it is outside the band at the end). Errors: true pose (not the robot's estimate) against the "
    "reference, every control tick; position = |(x_e, y_e)|, angle = |theta_e| (Eq 10).";

/// Bad command line; what() names the flag.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class Trajectory { kCircle, kLine, kWaypoints };

const char* toString(Trajectory t) {
  switch (t) {
    case Trajectory::kCircle: return "circle";
    case Trajectory::kLine: return "line";
    case Trajectory::kWaypoints: return "waypoints";
  }
  return "?";
}

struct Options {
  Trajectory trajectory = Trajectory::kCircle;
  double radius_m = 3.5;
  double speed_m_s = 0.5;
  double laps = 1.0;
  double length_m = 10.0;
  std::vector<WheelControl> controllers{WheelControl::kPid, WheelControl::kFuzzyPid};
  std::string robot_path = "config/robot.yaml";
  std::string control_path = "config/control.yaml";
  uint32_t seed = 1;
  int seeds = 1;
  bool noise = true;
  double band_m = 0.01;
  double band_rad = 0.01;
  std::string plots_dir;
  std::string json_path;
  bool help = false;
};

// ---------------------------------------------------------------- arguments

double parseNumber(const std::string& flag, const std::string& text) {
  double v = 0;
  const char* end = text.data() + text.size();
  const auto [p, ec] = std::from_chars(text.data(), end, v);
  if (ec != std::errc() || p != end || !std::isfinite(v))
    throw UsageError(flag + ": expected a number, got '" + text + "'");
  return v;
}

long parseInteger(const std::string& flag, const std::string& text, long min, long max) {
  long v = 0;
  const char* end = text.data() + text.size();
  const auto [p, ec] = std::from_chars(text.data(), end, v);
  if (ec != std::errc() || p != end || v < min || v > max)
    throw UsageError(flag + ": expected an integer in [" + std::to_string(min) + ", " + std::to_string(max) +
                     "], got '" + text + "'");
  return v;
}

double positive(const std::string& flag, double v) {
  if (!(v > 0)) throw UsageError(flag + ": must be positive");
  return v;
}

WheelControl parseController(const std::string& name) {
  if (name == "pid") return WheelControl::kPid;
  if (name == "fuzzy_pid") return WheelControl::kFuzzyPid;
  if (name == "direct") return WheelControl::kDirect;
  throw UsageError("--controllers: unknown controller '" + name + "' (pid, fuzzy_pid, direct)");
}

std::vector<WheelControl> parseControllers(const std::string& list) {
  std::vector<WheelControl> out;
  std::size_t begin = 0;
  while (begin <= list.size()) {
    const std::size_t comma = std::min(list.find(',', begin), list.size());
    const WheelControl c = parseController(list.substr(begin, comma - begin));
    if (std::find(out.begin(), out.end(), c) != out.end())
      throw UsageError("--controllers: '" + std::string(control::toString(c)) + "' given twice");
    out.push_back(c);
    begin = comma + 1;
  }
  return out;
}

Options parseArgs(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw UsageError(flag + ": missing value");
      return argv[++i];
    };
    if (flag == "--help" || flag == "-h") {
      o.help = true;
    } else if (flag == "--trajectory") {
      const std::string t = value();
      if (t == "circle") o.trajectory = Trajectory::kCircle;
      else if (t == "line") o.trajectory = Trajectory::kLine;
      else if (t == "waypoints") o.trajectory = Trajectory::kWaypoints;
      else throw UsageError("--trajectory: expected circle, line or waypoints, got '" + t + "'");
    } else if (flag == "--radius") {
      o.radius_m = parseNumber(flag, value());
      if (!(std::abs(o.radius_m) >= 0.05)) throw UsageError("--radius: |radius| must be at least 0.05 m");
    } else if (flag == "--speed") {
      o.speed_m_s = positive(flag, parseNumber(flag, value()));
    } else if (flag == "--laps") {
      o.laps = positive(flag, parseNumber(flag, value()));
    } else if (flag == "--length") {
      o.length_m = positive(flag, parseNumber(flag, value()));
    } else if (flag == "--controllers") {
      o.controllers = parseControllers(value());
    } else if (flag == "--robot") {
      o.robot_path = value();
    } else if (flag == "--control") {
      o.control_path = value();
    } else if (flag == "--seed") {
      o.seed = static_cast<uint32_t>(parseInteger(flag, value(), 0, 4294967295L));
    } else if (flag == "--seeds") {
      o.seeds = static_cast<int>(parseInteger(flag, value(), 1, 10000));
    } else if (flag == "--no-noise") {
      o.noise = false;
    } else if (flag == "--band-m") {
      o.band_m = positive(flag, parseNumber(flag, value()));
    } else if (flag == "--band-rad") {
      o.band_rad = positive(flag, parseNumber(flag, value()));
    } else if (flag == "--plots") {
      o.plots_dir = value();
    } else if (flag == "--json") {
      o.json_path = value();
    } else {
      throw UsageError(flag + ": unknown argument (see --help)");
    }
  }
  return o;
}

// ---------------------------------------------------------------- paths

std::unique_ptr<control::ReferencePath> makePath(const Options& o) {
  const control::Pose2 start{0.0, 0.0, 0.0};  // the paper's start (0, 0, 0)
  switch (o.trajectory) {
    case Trajectory::kCircle: return control::makeCircle(start, o.radius_m, o.speed_m_s, o.laps);
    case Trajectory::kLine: return control::makeLine(start, o.length_m, o.speed_m_s);
    case Trajectory::kWaypoints: return control::makeRectangleWaypoints(o.length_m, o.speed_m_s);
  }
  throw std::logic_error("unknown trajectory");
}

// ---------------------------------------------------------------- metrics

/// One row of the table: how to read it from a run, and the paper's figures.
struct MetricDef {
  const char* key;    // JSON key
  const char* label;  // table label
  int decimals;
  std::optional<double> paper_pid;
  std::optional<double> paper_fuzzy;
};

enum Metric : std::size_t {
  kMaxPos,
  kMaxAng,
  kConvPos,
  kConvAng,
  kRmsPos,
  kRmsAng,
  kEffort,
  kVariation,
  kSaturation,
  kNumMetrics
};

// Paper section 5.2 (PAPER_DIGEST.md): fuzzy-PID max position error "less
// than 0.098 m" converged 18.25 s, max angle error "less than 0.088 rad"
// converged 20.05 s; PID 0.1 m / 25.76 s and 0.175 rad / 20.52 s.
const std::array<MetricDef, kNumMetrics> kMetrics{{
    {"max_position_error_m", "max position error (m)", 4, 0.1, 0.098},
    {"max_angle_error_rad", "max angle error (rad)", 4, 0.175, 0.088},
    {"position_convergence_s", "position convergence (s)", 2, 25.76, 18.25},
    {"angle_convergence_s", "angle convergence (s)", 2, 20.52, 20.05},
    {"rms_position_error_m", "RMS position error (m)", 4, std::nullopt, std::nullopt},
    {"rms_angle_error_rad", "RMS angle error (rad)", 4, std::nullopt, std::nullopt},
    {"control_effort_rad2_s", "control effort (rad^2/s)", 1, std::nullopt, std::nullopt},
    {"command_variation_rad_s", "command variation (rad/s)", 1, std::nullopt, std::nullopt},
    {"saturation_time_s", "saturation time (s)", 2, std::nullopt, std::nullopt},
}};

/// One closed-loop run and what is derived from it.
struct Run {
  WheelControl controller;
  uint32_t seed;
  sim::ClosedLoopResult result;
  double final_ang_err_rad = 0;
  bool pos_converged = true;
  bool ang_converged = true;
  double wall_s = 0;
  std::array<double, kNumMetrics> values{};  // NaN: not converged
};

Run runOnce(const Options& o, const sim::ClosedLoopConfig& base, WheelControl wc, uint32_t seed,
            const std::shared_ptr<control::FuzzyGainScheduler>& sched) {
  sim::ClosedLoopConfig cfg = base;
  cfg.tracker.wheel_control = wc;
  cfg.seed = seed;
  Run r{wc, seed, {}};
  const auto t0 = Clock::now();
  r.result = sim::runClosedLoop(cfg, makePath(o), wc == WheelControl::kFuzzyPid ? sched : nullptr, true);
  r.wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  const auto& m = r.result.metrics;
  r.final_ang_err_rad = r.result.samples.empty() ? 0.0 : r.result.samples.back().ang_err_rad;
  // convergenceTime() cannot tell "entered the band at the last tick" from
  // "never entered it": the final error decides.
  r.pos_converged = !(m.final_pos_err_m > cfg.settle_position_m);
  r.ang_converged = !(r.final_ang_err_rad > cfg.settle_angle_rad);
  r.values = {m.max_pos_err_m,
              m.max_ang_err_rad,
              r.pos_converged ? m.converge_pos_s : kNaN,
              r.ang_converged ? m.converge_ang_s : kNaN,
              m.rms_pos_err_m,
              m.rms_ang_err_rad,
              m.effort,
              m.command_variation,
              m.saturated_s};
  return r;
}

/// A metric over seeds.
struct Stat {
  double mean = kNaN;
  double max = kNaN;
  int not_converged = 0;
};

Stat statOf(const std::vector<const Run*>& runs, std::size_t metric) {
  Stat s;
  double sum = 0, mx = -std::numeric_limits<double>::infinity();
  for (const Run* r : runs) {
    const double v = r->values[metric];
    if (std::isnan(v)) {
      ++s.not_converged;
      continue;
    }
    sum += v;
    mx = std::max(mx, v);
  }
  if (s.not_converged == 0 && !runs.empty()) {
    s.mean = sum / static_cast<double>(runs.size());
    s.max = mx;
  }
  return s;
}

std::string label(WheelControl c) {
  switch (c) {
    case WheelControl::kPid: return "PID";
    case WheelControl::kFuzzyPid: return "fuzzy-PID";
    case WheelControl::kDirect: return "direct";
  }
  return "?";
}

std::string fmt(double v, int decimals) {
  if (std::isnan(v)) return "not conv.";
  char b[48];
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}

std::string fmtPaper(const std::optional<double>& v) {
  if (!v) return "-";
  char b[32];
  std::snprintf(b, sizeof b, "%g", *v);
  return b;
}

// ---------------------------------------------------------------- Table 3

/// The paper's Table 3 "critical points": the start and each quarter lap.
struct CriticalPoint {
  double fraction;  // of one lap
  double paper_pos_m;
  double paper_ang_rad;
};
constexpr std::array<CriticalPoint, 5> kCritical{{{0.0, 0.0, 0.0},
                                                  {0.25, 0.014, 0.007},
                                                  {0.5, 0.001, 0.0},
                                                  {0.75, 0.0, 0.0},
                                                  {1.0, 0.0, 0.0}}};

/// Errors when the reference passes `fraction` of the first lap.
struct PointErrors {
  double t_s;
  double pos_m;
  double ang_rad;
};

/// The errors at a critical point; nothing if the run does not reach it.
/// Point 1 is the start, where the robot is placed: both errors are 0.
std::optional<PointErrors> errorsAtLapFraction(const Run& r, const Options& o, double fraction) {
  const auto& s = r.result.samples;
  if (s.empty() || fraction > o.laps + 1e-9) return std::nullopt;
  if (fraction <= 0) return PointErrors{0.0, 0.0, 0.0};
  const double t = fraction * 2.0 * std::numbers::pi * std::abs(o.radius_m) / o.speed_m_s;
  auto it = std::lower_bound(s.begin(), s.end(), t - 1e-9,
                             [](const sim::ClosedLoopSample& a, double tt) { return a.t_s < tt; });
  if (it == s.end()) --it;
  if (it != s.begin() && std::abs((it - 1)->t_s - t) < std::abs(it->t_s - t)) --it;
  return PointErrors{it->t_s, it->pos_err_m, it->ang_err_rad};
}

// ---------------------------------------------------------------- plots

const char* colorOf(WheelControl c) {
  switch (c) {
    case WheelControl::kPid: return "#d62728";
    case WheelControl::kFuzzyPid: return "#1f77b4";
    case WheelControl::kDirect: return "#2ca02c";
  }
  return "#000000";
}

std::string writePlots(const Options& o, const std::vector<const Run*>& runs, const control::PidGains& base,
                       std::vector<std::string>& written) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(o.plots_dir, ec);
  if (ec) return "cannot create " + o.plots_dir + ": " + ec.message();
  const std::string dir = o.plots_dir + "/";

  // Fig 18: reference vs actual trajectories, and the distance between them.
  {
    const auto ref_path = makePath(o);
    plot::Series ref = series("reference", "#000000", 2, true);
    const double ds = std::min(0.01, ref_path->length_m() / 2000);
    for (double s = 0; s <= ref_path->length_m() + 1e-9; s += ds) {
      const auto p = ref_path->at(s).pose;
      ref.x.push_back(p.x_m);
      ref.y.push_back(p.y_m);
    }
    auto whole = panel("Fig 18: reference and actual trajectories (" + ref_path->describe() + ")", "x (m)", "y (m)");
    whole.equal_axes = true;
    whole.key = "outside right top";
    auto dist = panel("Distance of the actual trajectory from the reference path (Fig 18 magnified; along-track lag "
                      "excluded)",
                      "t (s)", "distance (m)");
    for (const Run* r : runs) {
      auto actual = series(label(r->controller), colorOf(r->controller));
      auto d = series(label(r->controller), colorOf(r->controller), 1);
      d.y = sim::distanceFromPath(ref.x, ref.y, r->result.samples);
      for (const auto& smp : r->result.samples) {
        actual.x.push_back(smp.pose.x_m);
        actual.y.push_back(smp.pose.y_m);
        d.x.push_back(smp.t_s);
      }
      whole.series.push_back(std::move(actual));
      dist.series.push_back(std::move(d));
    }
    whole.series.push_back(std::move(ref));  // drawn last, on top
    const auto p0 = ref_path->at(0).pose;
    auto mark = series("start (0, 0, 0)", "#000000");
    mark.style = "points pt 7 ps 2";
    mark.x = {p0.x_m};
    mark.y = {p0.y_m};
    whole.series.push_back(std::move(mark));
    const std::string path = dir + "fig18_trajectory.png";
    if (auto err = plot::renderPng(path, {whole, dist}, 1000, 560); !err.empty()) return err;
    written.push_back(path);
  }

  // Fig 20: position (a) and angle (b) error vs time, band shaded, convergence marked.
  {
    auto pos = panel("Fig 20a: position error (grey: band " + fmt(o.band_m, 3) + " m; dotted: convergence time)",
                     "t (s)", "position error (m)");
    auto ang = panel("Fig 20b: angle error (grey: band " + fmt(o.band_rad, 3) + " rad; dotted: convergence time)",
                     "t (s)", "angle error (rad)");
    pos.bands.push_back({0.0, o.band_m, "#bbbbbb", "band"});
    ang.bands.push_back({0.0, o.band_rad, "#bbbbbb", "band"});
    for (const Run* r : runs) {
      auto pe = series(label(r->controller), colorOf(r->controller), 1);
      auto ae = series(label(r->controller), colorOf(r->controller), 1);
      for (const auto& smp : r->result.samples) {
        pe.x.push_back(smp.t_s);
        pe.y.push_back(smp.pos_err_m);
        ae.x.push_back(smp.t_s);
        ae.y.push_back(smp.ang_err_rad);
      }
      pos.series.push_back(std::move(pe));
      ang.series.push_back(std::move(ae));
      auto marker = [&](double t, double top) {
        auto m = series(label(r->controller) + " converged at " + fmt(t, 2) + " s", colorOf(r->controller));
        m.style = "lines dt 3";
        m.x = {t, t};
        m.y = {0.0, top};
        return m;
      };
      if (!std::isnan(r->values[kConvPos]))
        pos.series.push_back(marker(r->values[kConvPos], r->result.metrics.max_pos_err_m));
      if (!std::isnan(r->values[kConvAng]))
        ang.series.push_back(marker(r->values[kConvAng], r->result.metrics.max_ang_err_rad));
    }
    const std::string path = dir + "fig20_errors.png";
    if (auto err = plot::renderPng(path, {pos, ang}, 1000, 420); !err.empty()) return err;
    written.push_back(path);
  }

  // Wheel speeds and fuzzy-scheduled gains during the start transient, and kp over the whole run.
  {
    const double window_s = 3.0;
    auto wheels = panel("Wheel speeds, first " + fmt(window_s, 0) + " s (solid: left, dashed: right)", "t (s)",
                        "wheel speed (rad/s)");
    wheels.key = "bottom right";
    auto gains = panel("Gains of the left wheel loop, first " + fmt(window_s, 0) +
                           " s: fuzzy-scheduled (Eq 15, solid) and the PID's kp', ki', kd' (dashed)",
                       "t (s)", "gain");
    gains.key = "outside right top";
    auto kp_run = panel("Fuzzy-scheduled kp of the left wheel over the whole run (noise moves e and ec)", "t (s)",
                        "kp");
    kp_run.key = "outside right top";
    const auto& first = runs.front()->result.samples;
    const double t_end = first.empty() ? 0.0 : first.back().t_s;
    auto constant = [&](const std::string& name, double v, const char* color, double t1) {
      auto c = series(name, color, 2, true);
      c.x = {0.0, t1};
      c.y = {v, v};
      return c;
    };
    for (const Run* r : runs) {
      auto l = series(label(r->controller) + " left", colorOf(r->controller));
      auto rr = series(label(r->controller) + " right", colorOf(r->controller), 2, true);
      for (const auto& smp : r->result.samples) {
        if (smp.t_s > window_s) break;
        l.x.push_back(smp.t_s);
        l.y.push_back(smp.wheel.left_rad_s);
        rr.x.push_back(smp.t_s);
        rr.y.push_back(smp.wheel.right_rad_s);
      }
      wheels.series.push_back(std::move(l));
      wheels.series.push_back(std::move(rr));
      if (r->controller != WheelControl::kFuzzyPid) continue;
      auto kp = series("kp", "#1f77b4", 1), ki = series("ki", "#ff7f0e", 1), kd = series("kd", "#9467bd", 1);
      auto kp_all = series("kp (fuzzy)", "#1f77b4", 1);
      for (const auto& smp : r->result.samples) {
        kp_all.x.push_back(smp.t_s);
        kp_all.y.push_back(smp.gains_left.kp);
        if (smp.t_s > window_s) continue;
        kp.x.push_back(smp.t_s);
        kp.y.push_back(smp.gains_left.kp);
        ki.x.push_back(smp.t_s);
        ki.y.push_back(smp.gains_left.ki);
        kd.x.push_back(smp.t_s);
        kd.y.push_back(smp.gains_left.kd);
      }
      gains.series.push_back(std::move(kp));
      gains.series.push_back(std::move(ki));
      gains.series.push_back(std::move(kd));
      kp_run.series.push_back(std::move(kp_all));
    }
    gains.series.push_back(constant("kp'", base.kp, "#1f77b4", window_s));
    gains.series.push_back(constant("ki'", base.ki, "#ff7f0e", window_s));
    gains.series.push_back(constant("kd'", base.kd, "#9467bd", window_s));
    kp_run.series.push_back(constant("kp'", base.kp, "#000000", t_end));
    std::vector<plot::Panel> panels{wheels};
    if (gains.series.size() > 3) {  // a fuzzy-PID run is among them
      panels.push_back(std::move(gains));
      panels.push_back(std::move(kp_run));
    }
    const std::string path = dir + "wheels_gains.png";
    if (auto err = plot::renderPng(path, panels, 1000, 380); !err.empty()) return err;
    written.push_back(path);
  }
  return "";
}

// ---------------------------------------------------------------- output

nlohmann::ordered_json numberOrNull(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
}

int run(const Options& o) {
  // Configuration (errors are one line, exit 2).
  config::RobotConfig robot;
  config::ControlConfig ctl;
  std::shared_ptr<control::FuzzyGainScheduler> sched;
  robot = config::loadRobotConfigFile(o.robot_path);
  ctl = config::loadControlConfigFile(o.control_path);
  config::applyRobot(ctl, robot);
  const bool need_fuzzy =
      std::find(o.controllers.begin(), o.controllers.end(), WheelControl::kFuzzyPid) != o.controllers.end();
  if (need_fuzzy) sched = config::loadScheduler(ctl);

  sim::ClosedLoopConfig base;
  base.robot = robot;
  base.tracker = ctl.tracker;
  base.noise = o.noise;
  base.settle_position_m = o.band_m;
  base.settle_angle_rad = o.band_rad;
  const auto path_desc = makePath(o)->describe();

  // (a) set-up.
  std::printf("track_experiment: the paper's trajectory-tracking experiment (section 5.2, Figs 18, 20)\n");
  std::printf("  reference      %s, start (0, 0, 0)%s\n", path_desc.c_str(),
              o.trajectory == Trajectory::kCircle ? (o.radius_m > 0 ? ", counter-clockwise" : ", clockwise") : "");
  std::printf("  speed          %.3g m/s (ASSUMED: the paper does not state the tracking speed)\n", o.speed_m_s);
  std::printf("  control dt     %.3g s (paper: 0.01 s); plant integrated at %.3g s\n", base.control_dt_s,
              base.physics_dt_s);
  std::printf("  plant          first-order hub motors, tau %.3g s, |wheel| <= %.3g rad/s, r %.3g m, L %.3g m (%s)\n",
              robot.motor.time_constant_s, robot.limits.max_wheel_speed_rad_s, robot.geometry.wheel_radius_m,
              robot.geometry.track_m, o.robot_path.c_str());
  std::printf("  measurement    %s\n",
              o.noise ? ("noisy: wheel speed +-" + fmt(robot.motor.speed_noise_m_s, 3) + " m/s, heading +-" +
                         fmt(robot.motor.heading_noise_rad, 3) + " rad (uniform); seeds " + std::to_string(o.seed) +
                         (o.seeds > 1 ? ".." + std::to_string(o.seed + static_cast<uint32_t>(o.seeds) - 1) : ""))
                            .c_str()
                      : "exact (--no-noise)");
  const auto& t = ctl.tracker;
  std::printf("  tracker        Eq 12 a1 %g a2 %g a3 %g; wheel loop kp' %g ki' %g kd' %g, derivative filter %g s, "
              "integral limit %g rad/s, feedforward %s (%s)\n",
              t.aux.a1, t.aux.a2, t.aux.a3, t.fuzzy.base.kp, t.fuzzy.base.ki, t.fuzzy.base.kd,
              t.pid.derivative_filter_s, t.pid.integral_limit, t.feedforward ? "on" : "off", o.control_path.c_str());
  if (need_fuzzy)
    std::printf("  fuzzy-PID      %s (%s), ke %g kec %g k1 %g k2 %g k3 %g\n", ctl.fis_path.c_str(),
                ctl.use_lookup ? "lookup surface" : "direct inference", t.fuzzy.ke, t.fuzzy.kec, t.fuzzy.k1,
                t.fuzzy.k2, t.fuzzy.k3);
  std::printf("  bands          position %g m, angle %g rad\n", o.band_m, o.band_rad);
  std::printf("  %s\n\n", kConvergenceDefinition);

  // Runs.
  std::vector<Run> runs;
  const auto wall0 = Clock::now();
  for (const WheelControl wc : o.controllers)
    for (int k = 0; k < o.seeds; ++k) runs.push_back(runOnce(o, base, wc, o.seed + static_cast<uint32_t>(k), sched));
  const double wall_s = std::chrono::duration<double>(Clock::now() - wall0).count();
  double sim_s = 0;
  for (const auto& r : runs) sim_s += r.result.metrics.duration_s;

  auto runsOf = [&](WheelControl wc) {
    std::vector<const Run*> v;
    for (const auto& r : runs)
      if (r.controller == wc) v.push_back(&r);
    return v;
  };

  // (b) table; the paper's figures are for its circle only.
  const bool is_circle = o.trajectory == Trajectory::kCircle;
  const bool multi = o.seeds > 1;
  std::printf("Results%s\n", multi ? (" over " + std::to_string(o.seeds) + " seeds: mean / max").c_str() : "");
  const int w0 = 28, wc = multi ? 22 : 12;
  std::printf("%-*s", w0, "metric");
  for (const auto c : o.controllers) std::printf(" %*s", wc, label(c).c_str());
  if (is_circle) std::printf(" %11s %11s", "paper PID", "paper fPID");
  std::printf("\n");
  for (std::size_t m = 0; m < kNumMetrics; ++m) {
    const auto& d = kMetrics[m];
    std::printf("%-*s", w0, d.label);
    for (const auto c : o.controllers) {
      const Stat s = statOf(runsOf(c), m);
      std::string cell = multi ? fmt(s.mean, d.decimals) + " / " + fmt(s.max, d.decimals) : fmt(s.mean, d.decimals);
      if (multi && s.not_converged) cell = "not conv. (" + std::to_string(s.not_converged) + " seeds)";
      std::printf(" %*s", wc, cell.c_str());
    }
    if (is_circle) std::printf(" %11s %11s", fmtPaper(d.paper_pid).c_str(), fmtPaper(d.paper_fuzzy).c_str());
    std::printf("\n");
  }
  if (is_circle)
    std::printf("paper (section 5.2): fuzzy-PID max errors 'less than' 0.098 m / 0.088 rad; its convergence band, "
                "speed and plant are not stated.\n");
  std::printf("effort = integral of (u_l^2 + u_r^2) dt over the wheel commands; command variation = sum of "
              "|u(k) - u(k-1)| over both wheels;\nsaturation time = time with a wheel command at the wheel-speed "
              "limit.\n");

  // Table 3 comparison (circle, first seed).
  const bool critical = is_circle;
  if (critical) {
    std::printf("\nErrors at the paper's Table 3 critical points (start and quarter laps; seed %u; paper: real robot)\n",
                o.seed);
    std::printf("%-10s %8s", "point", "t (s)");
    for (const auto c : o.controllers) std::printf(" %22s", (label(c) + " m / rad").c_str());
    std::printf(" %22s\n", "paper m / rad");
    for (std::size_t k = 0; k < kCritical.size(); ++k) {
      const auto& cp = kCritical[k];
      if (cp.fraction > o.laps + 1e-9) break;
      const double tt = cp.fraction * 2.0 * std::numbers::pi * std::abs(o.radius_m) / o.speed_m_s;
      std::printf("%-10s %8.2f", (std::to_string(k + 1) + " (" + fmt(cp.fraction, 2) + ")").c_str(), tt);
      for (const auto c : o.controllers) {
        const auto pe = errorsAtLapFraction(*runsOf(c).front(), o, cp.fraction);
        std::printf(" %22s", pe ? (fmt(pe->pos_m, 3) + " / " + fmt(pe->ang_rad, 3)).c_str() : "-");
      }
      std::printf(" %22s\n", (fmt(cp.paper_pos_m, 3) + " / " + fmt(cp.paper_ang_rad, 3)).c_str());
    }
  }

  // (c) speed.
  std::printf("\n%zu run(s), %.1f simulated s in %.3f s wall time: %.0f simulated s per wall s\n", runs.size(), sim_s,
              wall_s, wall_s > 0 ? sim_s / wall_s : kNaN);

  int status = 0;
  std::vector<std::string> pngs;
  if (!o.plots_dir.empty()) {
    std::vector<const Run*> firsts;
    for (const auto c : o.controllers) firsts.push_back(runsOf(c).front());
    if (const auto err = writePlots(o, firsts, t.fuzzy.base, pngs); !err.empty()) {
      std::fprintf(stderr, "track_experiment: plots: %s\n", err.c_str());
      status = 1;
    }
    for (const auto& p : pngs) std::printf("plot: %s\n", p.c_str());
  }

  if (!o.json_path.empty()) {
    nlohmann::ordered_json j;
    j["experiment"] = "trajectory tracking (paper section 5.2, Figs 18, 20, Table 3)";
    j["setup"] = {{"trajectory", toString(o.trajectory)},
                  {"reference", path_desc},
                  {"start", {0.0, 0.0, 0.0}},
                  {"radius_m", o.radius_m},
                  {"speed_m_s", o.speed_m_s},
                  {"speed_assumed", true},
                  {"laps", o.laps},
                  {"length_m", o.length_m},
                  {"control_dt_s", base.control_dt_s},
                  {"physics_dt_s", base.physics_dt_s},
                  {"noise", o.noise},
                  {"seed", o.seed},
                  {"seeds", o.seeds},
                  {"band_m", o.band_m},
                  {"band_rad", o.band_rad},
                  {"motor_time_constant_s", robot.motor.time_constant_s},
                  {"derivative_filter_s", t.pid.derivative_filter_s},
                  {"feedforward", t.feedforward},
                  {"fis", need_fuzzy ? ctl.fis_path : ""},
                  {"fis_lookup", ctl.use_lookup},
                  {"robot_config", o.robot_path},
                  {"control_config", o.control_path}};
    j["convergence_definition"] = kConvergenceDefinition;
    auto& ctrl = j["controllers"];
    for (const auto c : o.controllers) {
      nlohmann::ordered_json cj;
      const auto rs = runsOf(c);
      for (std::size_t m = 0; m < kNumMetrics; ++m) {
        const Stat s = statOf(rs, m);
        nlohmann::ordered_json per_seed = nlohmann::ordered_json::array();
        for (const Run* r : rs) per_seed.push_back(numberOrNull(r->values[m]));
        cj[kMetrics[m].key] = {{"mean", numberOrNull(s.mean)},
                               {"max", numberOrNull(s.max)},
                               {"not_converged", s.not_converged},
                               {"per_seed", per_seed}};
      }
      ctrl[control::toString(c)] = cj;
    }
    auto& paper = j["paper"];
    for (std::size_t m = 0; m < kNumMetrics; ++m) {
      const auto& d = kMetrics[m];
      if (d.paper_pid || d.paper_fuzzy)
        paper[d.key] = {{"pid", d.paper_pid ? nlohmann::ordered_json(*d.paper_pid) : nullptr},
                        {"fuzzy_pid", d.paper_fuzzy ? nlohmann::ordered_json(*d.paper_fuzzy) : nullptr}};
    }
    if (critical) {
      auto& cps = j["critical_points"];
      cps = nlohmann::ordered_json::array();
      for (std::size_t k = 0; k < kCritical.size(); ++k) {
        const auto& cp = kCritical[k];
        if (cp.fraction > o.laps + 1e-9) break;
        nlohmann::ordered_json e{{"point", k + 1},
                                 {"lap_fraction", cp.fraction},
                                 {"paper_position_error_m", cp.paper_pos_m},
                                 {"paper_angle_error_rad", cp.paper_ang_rad}};
        for (const auto c : o.controllers)
          if (const auto pe = errorsAtLapFraction(*runsOf(c).front(), o, cp.fraction))
            e[control::toString(c)] = {{"t_s", pe->t_s}, {"position_error_m", pe->pos_m},
                                       {"angle_error_rad", pe->ang_rad}};
        cps.push_back(e);
      }
    }
    j["timing"] = {{"runs", runs.size()},
                   {"simulated_s", sim_s},
                   {"wall_s", wall_s},
                   {"simulated_s_per_wall_s", numberOrNull(wall_s > 0 ? sim_s / wall_s : kNaN)}};
    j["plots"] = pngs;
    std::ofstream f(o.json_path);
    f << j.dump(2) << "\n";
    if (!f) {
      std::fprintf(stderr, "track_experiment: cannot write %s\n", o.json_path.c_str());
      status = 1;
    } else {
      std::printf("json: %s\n", o.json_path.c_str());
    }
  }
  return status;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  try {
    o = parseArgs(argc, argv);
  } catch (const UsageError& e) {
    std::fprintf(stderr, "track_experiment: %s\n", e.what());
    return 2;
  }
  if (o.help) {
    std::fputs(kUsage, stdout);
    return 0;
  }
  try {
    return run(o);
  } catch (const config::ConfigError& e) {
    std::fprintf(stderr, "track_experiment: %s\n", e.what());
    return 2;
  } catch (const std::invalid_argument& e) {  // a path the reference builders refuse
    std::fprintf(stderr, "track_experiment: %s\n", e.what());
    return 2;
  }
}
