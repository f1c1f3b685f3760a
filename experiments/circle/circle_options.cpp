// track_experiment's command line and the parts of a run every file shares.
#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "experiments/circle/circle_experiment.hpp"

namespace inspect::circle {

const char* const kUsage = R"(usage: track_experiment [options]
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
  --dead-time S     the motors' dead time, s: the latency from a command to the
                    wheels, as a serial link and an MCU add it (default 0)
  --band-m M        position convergence band, m (default 0.01)
  --band-rad R      angle convergence band, rad (default 0.01)
  --plots DIR       write Fig 18 / Fig 20 / wheel-and-gain PNGs into DIR
  --json FILE       write the figures as JSON
  --help            this text
Exit status: 0 done, 1 a plot or the JSON could not be written, 2 bad arguments or config.
)";

const char* toString(Trajectory t) {
  switch (t) {
    case Trajectory::kCircle: return "circle";
    case Trajectory::kLine: return "line";
    case Trajectory::kWaypoints: return "waypoints";
  }
  return "?";
}

WheelControl parseController(const std::string& name) {
  if (name == "pid") return WheelControl::kPid;
  if (name == "fuzzy_pid") return WheelControl::kFuzzyPid;
  if (name == "direct") return WheelControl::kDirect;
  throw UsageError("--controllers: unknown controller '" + name + "' (pid, fuzzy_pid, direct)");
}

Options parseArgs(int argc, char** argv) {
  Options o;
  cli::ArgReader a(argc, argv);
  while (a.next()) {
    if (a.isHelp()) {
      o.help = true;
    } else if (a.is("--trajectory")) {
      const std::string t = a.choice({"circle", "line", "waypoints"});
      o.trajectory = t == "circle" ? Trajectory::kCircle : t == "line" ? Trajectory::kLine : Trajectory::kWaypoints;
    } else if (a.is("--radius")) {
      o.radius_m = a.number();
      if (!(std::abs(o.radius_m) >= 0.05)) a.fail("|radius| must be at least 0.05 m");
    } else if (a.is("--speed")) {
      o.speed_m_s = a.numberAbove(0);
    } else if (a.is("--laps")) {
      o.laps = a.numberAbove(0);
    } else if (a.is("--length")) {
      o.length_m = a.numberAbove(0);
    } else if (a.is("--controllers")) {
      o.controllers.clear();
      for (const auto& name : a.list()) {
        const WheelControl c = parseController(name);
        if (std::find(o.controllers.begin(), o.controllers.end(), c) != o.controllers.end())
          a.fail("'" + std::string(control::toString(c)) + "' given twice");
        o.controllers.push_back(c);
      }
    } else if (a.is("--robot")) {
      o.robot_path = a.path();
    } else if (a.is("--control")) {
      o.control_path = a.path();
    } else if (a.is("--seed")) {
      o.seed = static_cast<uint32_t>(a.integer(0, 4294967295LL));
    } else if (a.is("--seeds")) {
      o.seeds = static_cast<int>(a.integer(1, 10000));
    } else if (a.is("--no-noise")) {
      o.noise = false;
    } else if (a.is("--dead-time")) {
      o.dead_time_s = a.number(0.0, 1.0);
    } else if (a.is("--band-m")) {
      o.band_m = a.numberAbove(0);
    } else if (a.is("--band-rad")) {
      o.band_rad = a.numberAbove(0);
    } else if (a.is("--plots")) {
      o.plots_dir = a.path();
    } else if (a.is("--json")) {
      o.json_path = a.path();
    } else {
      a.unknown();
    }
  }
  return o;
}

std::unique_ptr<control::ReferencePath> makePath(const Options& o) {
  const control::Pose2 start{0.0, 0.0, 0.0};  // the paper's start (0, 0, 0)
  switch (o.trajectory) {
    case Trajectory::kCircle: return control::makeCircle(start, o.radius_m, o.speed_m_s, o.laps);
    case Trajectory::kLine: return control::makeLine(start, o.length_m, o.speed_m_s);
    case Trajectory::kWaypoints: return control::makeRectangleWaypoints(o.length_m, o.speed_m_s);
  }
  throw std::logic_error("unknown trajectory");
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

}  // namespace inspect::circle
