// The circle experiment's plots: Fig 18 (trajectories), Fig 20 (errors with
// the convergence band), and the wheel speeds and gains of the first seconds.
#include <algorithm>
#include <cmath>
#include <filesystem>

#include "experiments/circle/circle_experiment.hpp"
#include "shared/util/gnuplot.hpp"

namespace inspect::circle {
namespace {
using plot::panel;
using plot::series;

const char* colorOf(WheelControl c) {
  switch (c) {
    case WheelControl::kPid: return "#d62728";
    case WheelControl::kFuzzyPid: return "#1f77b4";
    case WheelControl::kDirect: return "#2ca02c";
  }
  return "#000000";
}

// Fig 18: reference vs actual trajectories, and the distance between them.
std::string plotTrajectories(const Options& o, const std::vector<const Run*>& runs, const std::string& dir,
                 std::vector<std::string>& written) {
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
    auto trace = sim::trackTrace(ref.x, ref.y, r->result.samples);
    actual.x = std::move(trace.x_m);
    actual.y = std::move(trace.y_m);
    d.x = std::move(trace.t_s);
    d.y = std::move(trace.distance_m);
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
  return "";
}

// Fig 20: position (a) and angle (b) error vs time, band shaded, convergence marked.
std::string plotErrors(const Options& o, const std::vector<const Run*>& runs, const std::string& dir,
                 std::vector<std::string>& written) {
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
  return "";
}

// Wheel speeds and fuzzy-scheduled gains during the start transient, and kp over the whole run.
std::string plotWheelsAndGains(const std::vector<const Run*>& runs, const control::PidGains& base, const std::string& dir,
                 std::vector<std::string>& written) {
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
  return "";
}
}  // namespace

std::string writePlots(const Options& o, const std::vector<const Run*>& runs, const control::PidGains& base,
                       std::vector<std::string>& written) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(o.plots_dir, ec);
  if (ec) return "cannot create " + o.plots_dir + ": " + ec.message();
  const std::string dir = o.plots_dir + "/";
  if (auto err = plotTrajectories(o, runs, dir, written); !err.empty()) return err;
  if (auto err = plotErrors(o, runs, dir, written); !err.empty()) return err;
  return plotWheelsAndGains(runs, base, dir, written);
}

}  // namespace inspect::circle
