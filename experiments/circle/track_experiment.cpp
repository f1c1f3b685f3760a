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
#include "experiments/circle/circle_experiment.hpp"
#include "sim/closed_loop.hpp"
#include "sim/robot_plant.hpp"

namespace {

using namespace inspect;
using namespace inspect::circle;
using Clock = std::chrono::steady_clock;
using plot::panel;
using plot::series;

constexpr const char* kConvergenceDefinition =
    "convergence time = the first control tick after the LAST tick whose error exceeded the band, i.e. the "
    "time after which the error stays within the band until the end of the run (0 if it never left the band; "
    "'not conv.' if it is outside the band at the end). Errors: true pose (not the robot's estimate) against the "
    "reference, every control tick; position = |(x_e, y_e)|, angle = |theta_e| (Eq 10).";

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

std::string fmtPaper(const std::optional<double>& v) {
  if (!v) return "-";
  char b[32];
  std::snprintf(b, sizeof b, "%g", *v);
  return b;
}

// ---------------------------------------------------------------- output

nlohmann::ordered_json numberOrNull(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
}

/// The robot, the control config, the fuzzy scheduler when a fuzzy-PID runs,
/// the closed loop's base settings and the reference's description.
struct Setup {
  config::RobotConfig robot;
  config::ControlConfig ctl;
  std::shared_ptr<control::FuzzyGainScheduler> sched;
  bool need_fuzzy = false;
  sim::ClosedLoopConfig base;
  std::string path_desc;
};

/// The configuration (errors are one line, exit 2: ConfigError).
Setup loadSetup(const Options& o) {
  Setup st;
  st.robot = config::loadRobotConfigFile(o.robot_path);
  st.ctl = config::loadControlConfigFile(o.control_path);
  config::applyRobot(st.ctl, st.robot);
  st.need_fuzzy =
      std::find(o.controllers.begin(), o.controllers.end(), WheelControl::kFuzzyPid) != o.controllers.end();
  if (st.need_fuzzy) st.sched = config::loadScheduler(st.ctl);
  st.base.robot = st.robot;
  st.base.tracker = st.ctl.tracker;
  st.base.noise = o.noise;
  if (o.dead_time_s > 0.0) {
    st.base.plant = sim::nominalPlant(st.robot);
    st.base.plant->left.dead_time_s = st.base.plant->right.dead_time_s = o.dead_time_s;
  }
  st.base.settle_position_m = o.band_m;
  st.base.settle_angle_rad = o.band_rad;
  st.path_desc = makePath(o)->describe();
  return st;
}

/// (a) The set-up, as the paper's experiment and ours differ.
void printSetup(const Options& o, const Setup& st) {
  std::printf("track_experiment: the paper's trajectory-tracking experiment (section 5.2, Figs 18, 20)\n");
  std::printf("  reference      %s, start (0, 0, 0)%s\n", st.path_desc.c_str(),
              o.trajectory == Trajectory::kCircle ? (o.radius_m > 0 ? ", counter-clockwise" : ", clockwise") : "");
  std::printf("  speed          %.3g m/s (ASSUMED: the paper does not state the tracking speed)\n", o.speed_m_s);
  std::printf("  control dt     %.3g s (paper: 0.01 s); plant integrated at %.3g s\n", st.base.control_dt_s,
              st.base.physics_dt_s);
  std::printf("  plant          first-order hub motors, tau %.3g s, |wheel| <= %.3g rad/s, r %.3g m, L %.3g m (%s)\n",
              st.robot.motor.time_constant_s, st.robot.limits.max_wheel_speed_rad_s, st.robot.geometry.wheel_radius_m,
              st.robot.geometry.track_m, o.robot_path.c_str());
  std::printf("  measurement    %s\n",
              o.noise ? ("noisy: wheel speed +-" + fmt(st.robot.motor.speed_noise_m_s, 3) + " m/s, heading +-" +
                         fmt(st.robot.motor.heading_noise_rad, 3) + " rad (uniform); seeds " + std::to_string(o.seed) +
                         (o.seeds > 1 ? ".." + std::to_string(o.seed + static_cast<uint32_t>(o.seeds) - 1) : ""))
                            .c_str()
                      : "exact (--no-noise)");
  const auto& t = st.ctl.tracker;
  std::printf("  tracker        Eq 12 a1 %g a2 %g a3 %g; wheel loop kp' %g ki' %g kd' %g, derivative filter %g s, "
              "integral limit %g rad/s, feedforward %s (%s)\n",
              t.aux.a1, t.aux.a2, t.aux.a3, t.fuzzy.base.kp, t.fuzzy.base.ki, t.fuzzy.base.kd,
              t.pid.derivative_filter_s, t.pid.integral_limit, t.feedforward ? "on" : "off", o.control_path.c_str());
  if (st.need_fuzzy)
    std::printf("  fuzzy-PID      %s (%s), ke %g kec %g k1 %g k2 %g k3 %g\n", st.ctl.fis_path.c_str(),
                st.ctl.use_lookup ? "lookup surface" : "direct inference", t.fuzzy.ke, t.fuzzy.kec, t.fuzzy.k1,
                t.fuzzy.k2, t.fuzzy.k3);
  std::printf("  bands          position %g m, angle %g rad\n", o.band_m, o.band_rad);
  std::printf("  %s\n\n", kConvergenceDefinition);
}

/// The runs of one wheel controller, seed by seed.
std::vector<const Run*> runsOf(const std::vector<Run>& runs, WheelControl wc) {
  std::vector<const Run*> v;
  for (const auto& r : runs)
    if (r.controller == wc) v.push_back(&r);
  return v;
}

/// (b) The metrics per controller (mean / max over seeds); the paper's figures are for its circle only.
void printResults(const Options& o, const std::vector<Run>& runs) {
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
      const Stat s = statOf(runsOf(runs, c), m);
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

}

/// Errors at the paper's Table 3 critical points (circle, first seed).
void printCriticalPoints(const Options& o, const std::vector<Run>& runs) {
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
      const auto pe = errorsAtLapFraction(*runsOf(runs, c).front(), o, cp.fraction);
      std::printf(" %22s", pe ? (fmt(pe->pos_m, 3) + " / " + fmt(pe->ang_rad, 3)).c_str() : "-");
    }
    std::printf(" %22s\n", (fmt(cp.paper_pos_m, 3) + " / " + fmt(cp.paper_ang_rad, 3)).c_str());
  }
}

/// The plots (--plots); false (printed why) when one could not be written.
bool writeFigures(const Options& o, const Setup& st, const std::vector<Run>& runs, std::vector<std::string>& pngs) {
  bool ok = true;
  std::vector<const Run*> firsts;
  for (const auto c : o.controllers) firsts.push_back(runsOf(runs, c).front());
  if (const auto err = writePlots(o, firsts, st.ctl.tracker.fuzzy.base, pngs); !err.empty()) {
    std::fprintf(stderr, "track_experiment: plots: %s\n", err.c_str());
    ok = false;
  }
  for (const auto& p : pngs) std::printf("plot: %s\n", p.c_str());
  return ok;
}

/// The figures as JSON (--json); false (printed why) when the file cannot be written.
bool writeJson(const Options& o, const Setup& st, const std::vector<Run>& runs, double sim_s, double wall_s,
               const std::vector<std::string>& pngs) {
  const auto& t = st.ctl.tracker;
  nlohmann::ordered_json j;
  j["experiment"] = "trajectory tracking (paper section 5.2, Figs 18, 20, Table 3)";
  j["setup"] = {{"trajectory", toString(o.trajectory)},
                {"reference", st.path_desc},
                {"start", {0.0, 0.0, 0.0}},
                {"radius_m", o.radius_m},
                {"speed_m_s", o.speed_m_s},
                {"speed_assumed", true},
                {"laps", o.laps},
                {"length_m", o.length_m},
                {"control_dt_s", st.base.control_dt_s},
                {"physics_dt_s", st.base.physics_dt_s},
                {"noise", o.noise},
                {"seed", o.seed},
                {"seeds", o.seeds},
                {"band_m", o.band_m},
                {"band_rad", o.band_rad},
                {"motor_time_constant_s", st.robot.motor.time_constant_s},
                {"derivative_filter_s", t.pid.derivative_filter_s},
                {"feedforward", t.feedforward},
                {"fis", st.need_fuzzy ? st.ctl.fis_path : ""},
                {"fis_lookup", st.ctl.use_lookup},
                {"robot_config", o.robot_path},
                {"control_config", o.control_path}};
  j["convergence_definition"] = kConvergenceDefinition;
  auto& ctrl = j["controllers"];
  for (const auto c : o.controllers) {
    nlohmann::ordered_json cj;
    const auto rs = runsOf(runs, c);
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
  if (o.trajectory == Trajectory::kCircle) {
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
        if (const auto pe = errorsAtLapFraction(*runsOf(runs, c).front(), o, cp.fraction))
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
    return false;
  }
  std::printf("json: %s\n", o.json_path.c_str());
  return true;
}

int run(const Options& o) {
  const Setup st = loadSetup(o);
  printSetup(o, st);
  // The runs: each controller on each seed.
  std::vector<Run> runs;
  const auto wall0 = Clock::now();
  for (const WheelControl wc : o.controllers)
    for (int k = 0; k < o.seeds; ++k) runs.push_back(runOnce(o, st.base, wc, o.seed + static_cast<uint32_t>(k), st.sched));
  const double wall_s = std::chrono::duration<double>(Clock::now() - wall0).count();
  double sim_s = 0;
  for (const auto& r : runs) sim_s += r.result.metrics.duration_s;

  printResults(o, runs);
  if (o.trajectory == Trajectory::kCircle) printCriticalPoints(o, runs);
  // (c) speed.
  std::printf("\n%zu run(s), %.1f simulated s in %.3f s wall time: %.0f simulated s per wall s\n", runs.size(), sim_s,
              wall_s, wall_s > 0 ? sim_s / wall_s : kNaN);

  int status = 0;
  std::vector<std::string> pngs;
  if (!o.plots_dir.empty() && !writeFigures(o, st, runs, pngs)) status = 1;
  if (!o.json_path.empty() && !writeJson(o, st, runs, sim_s, wall_s, pngs)) status = 1;
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
