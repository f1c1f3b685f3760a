#include "pc_server/tuning/tuning_report.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "shared/config/gains_file.hpp"
#include "shared/util/file_util.hpp"
#include "shared/util/gnuplot.hpp"
#include "shared/util/number_text.hpp"

namespace inspect::tuning {

namespace {

namespace fs = std::filesystem;
using plot::panel;
using plot::series;
using Json = nlohmann::ordered_json;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The convergence bands of the closed loop the tuner runs (sim::ClosedLoopConfig defaults).
const sim::ClosedLoopConfig kLoopDefaults{};

// Colours by case order: the first three match track_experiment's PID / fuzzy-PID / direct.
constexpr const char* kPalette[] = {"#d62728", "#1f77b4", "#2ca02c", "#ff7f0e", "#9467bd",
                                    "#8c564b", "#e377c2", "#17becf", "#7f7f7f", "#bcbd22"};

const char* colorOf(std::size_t i) { return kPalette[i % std::size(kPalette)]; }

std::string fmtOrNotConverged(double v, int decimals) {
  if (std::isnan(v)) return "not conv.";
  char b[48];
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}

std::string fmtG(double v) { return util::significant(v, 6); }

Json numberOrNull(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

std::string describeWheel(const control::WheelMotorModel& m) {
  std::ostringstream os;
  os << "gain " << fmtG(m.gain) << ", time constant " << fmtG(m.time_constant_s) << " s, dead time "
     << fmtG(m.dead_time_s) << " s, |set-point| <= " << fmtG(m.saturation_rad_s) << " rad/s";
  return os.str();
}

std::string describePlant(const control::PlantModel& p) {
  const auto same = [](const control::WheelMotorModel& a, const control::WheelMotorModel& b) {
    return a.gain == b.gain && a.time_constant_s == b.time_constant_s && a.dead_time_s == b.dead_time_s &&
           a.saturation_rad_s == b.saturation_rad_s;
  };
  if (same(p.left, p.right)) return "both wheels: " + describeWheel(p.left);
  return "left: " + describeWheel(p.left) + "; right: " + describeWheel(p.right);
}

Json wheelJson(const control::WheelMotorModel& m) {
  return {{"gain", m.gain},
          {"time_constant_s", m.time_constant_s},
          {"dead_time_s", m.dead_time_s},
          {"saturation_rad_s", m.saturation_rad_s}};
}

Json gainsObject(const control::GainSet& g) { return Json::parse(config::gainsJson(g)); }

// ---------------------------------------------------------------- metrics

/// Convergence as track_experiment reports it: convergenceTime() cannot tell
/// "entered the band at the last tick" from "never entered it", so the final
/// error decides (NaN: not converged).
double positionConvergence(const sim::ClosedLoopResult& r) {
  return r.metrics.final_pos_err_m > kLoopDefaults.settle_position_m ? kNaN : r.metrics.converge_pos_s;
}
double angleConvergence(const sim::ClosedLoopResult& r) {
  const double final_ang = r.samples.empty() ? 0.0 : r.samples.back().ang_err_rad;
  return final_ang > kLoopDefaults.settle_angle_rad ? kNaN : r.metrics.converge_ang_s;
}

/// One row of the comparison table (wording as track_experiment's).
struct MetricRow {
  const char* key;    // JSON key
  const char* label;  // table label
  int decimals;
  double (*value)(const ComparisonRow&);
};

const MetricRow kRows[] = {
    {"max_position_error_m", "max position error (m)", 4,
     [](const ComparisonRow& r) { return r.trace.metrics.max_pos_err_m; }},
    {"rms_position_error_m", "RMS position error (m)", 4,
     [](const ComparisonRow& r) { return r.trace.metrics.rms_pos_err_m; }},
    {"max_angle_error_rad", "max angle error (rad)", 4,
     [](const ComparisonRow& r) { return r.trace.metrics.max_ang_err_rad; }},
    {"rms_angle_error_rad", "RMS angle error (rad)", 4,
     [](const ComparisonRow& r) { return r.trace.metrics.rms_ang_err_rad; }},
    {"position_convergence_s", "position convergence (s)", 2,
     [](const ComparisonRow& r) { return positionConvergence(r.trace); }},
    {"angle_convergence_s", "angle convergence (s)", 2,
     [](const ComparisonRow& r) { return angleConvergence(r.trace); }},
    {"control_effort_rad2_s", "control effort (rad^2/s)", 1,
     [](const ComparisonRow& r) { return r.trace.metrics.effort; }},
    {"saturation_time_s", "saturation time (s)", 2, [](const ComparisonRow& r) { return r.trace.metrics.saturated_s; }},
};

const MetricRow kRobustRows[] = {
    {"worst_max_position_error_m", "worst max position error (m)", 4,
     [](const ComparisonRow& r) { return r.eval.worst.max_pos_err_m; }},
    {"worst_max_angle_error_rad", "worst max angle error (rad)", 4,
     [](const ComparisonRow& r) { return r.eval.worst.max_ang_err_rad; }},
    {"cost", "cost (mean + worst scenario)", 3, [](const ComparisonRow& r) { return r.eval.cost; }},
};

Json metricsJson(const sim::ClosedLoopMetrics& m) {
  return {{"max_position_error_m", m.max_pos_err_m},
          {"rms_position_error_m", m.rms_pos_err_m},
          {"max_angle_error_rad", m.max_ang_err_rad},
          {"rms_angle_error_rad", m.rms_ang_err_rad},
          {"position_convergence_s", m.converge_pos_s},
          {"angle_convergence_s", m.converge_ang_s},
          {"control_effort_rad2_s", m.effort},
          {"command_variation_rad_s", m.command_variation},
          {"saturation_time_s", m.saturated_s},
          {"duration_s", m.duration_s},
          {"final_position_error_m", m.final_pos_err_m}};
}

// ---------------------------------------------------------------- plots

/// Fig 20-style error vs time, one curve per case, band shaded, convergence dotted.
plot::Panel errorPanel(const Comparison& c, bool position) {
  const double band = position ? kLoopDefaults.settle_position_m : kLoopDefaults.settle_angle_rad;
  auto p = panel(std::string(position ? "Fig 20a: position error" : "Fig 20b: angle error") + " vs time, " +
                     c.reference + ", the tuning plant (grey: band " + fmtG(band) + (position ? " m" : " rad") +
                     "; dotted: convergence time)",
                 "t (s)", position ? "position error (m)" : "angle error (rad)");
  p.bands.push_back({0.0, band, "#bbbbbb", "band"});
  p.yrange = "[0:*]";
  for (std::size_t i = 0; i < c.rows.size(); ++i) {
    const auto& row = c.rows[i];
    auto s = series(row.label, colorOf(i), 1);
    for (const auto& smp : row.trace.samples) {
      s.x.push_back(smp.t_s);
      s.y.push_back(position ? smp.pos_err_m : smp.ang_err_rad);
    }
    p.series.push_back(std::move(s));
  }
  // Markers after the curves so that the legend lists the cases first.
  for (std::size_t i = 0; i < c.rows.size(); ++i) {
    const auto& row = c.rows[i];
    const double t = position ? positionConvergence(row.trace) : angleConvergence(row.trace);
    if (std::isnan(t) || t <= 0) continue;
    const double top = position ? row.trace.metrics.max_pos_err_m : row.trace.metrics.max_ang_err_rad;
    auto m = series(row.label + " converged at " + fmtOrNotConverged(t, 2) + " s", colorOf(i));
    m.style = "lines dt 3";
    m.x = {t, t};
    m.y = {0.0, top};
    p.series.push_back(std::move(m));
  }
  return p;
}

/// The x-y paths with the reference, and their distance from the reference
/// path over time (the paths differ by centimetres on metres of path).
std::vector<plot::Panel> trajectoryPanels(const Comparison& c, const TuneReference& ref) {
  auto xy = panel("Reference and actual trajectories (" + c.reference + ", the tuning plant, seed 1)", "x (m)", "y (m)");
  xy.equal_axes = true;
  xy.key = "outside right top";
  auto dist = panel("Distance of each trajectory from the reference path (the top panel magnified; along-track lag "
                    "excluded)",
                    "t (s)", "distance from the path (m)");
  dist.yrange = "[0:*]";
  auto r = series("reference", "#000000", 2, true);
  const auto path = ref.makePath();
  const double len = path->length_m();
  const double ds = std::min(0.01, std::max(1e-3, len / 2000.0));
  for (double s = 0; s <= len + 1e-9; s += ds) {
    const auto pose = path->at(std::min(s, len)).pose;
    r.x.push_back(pose.x_m);
    r.y.push_back(pose.y_m);
  }
  for (std::size_t i = 0; i < c.rows.size(); ++i) {
    auto s = series(c.rows[i].label, colorOf(i));
    auto d = series(c.rows[i].label, colorOf(i), 1);
    auto trace = sim::trackTrace(r.x, r.y, c.rows[i].trace.samples);
    s.x = std::move(trace.x_m);
    s.y = std::move(trace.y_m);
    d.x = std::move(trace.t_s);
    d.y = std::move(trace.distance_m);
    xy.series.push_back(std::move(s));
    dist.series.push_back(std::move(d));
  }
  xy.series.push_back(std::move(r));  // drawn last, on top
  const auto p0 = path->at(0.0).pose;
  auto mark = series("start", "#000000");
  mark.style = "points pt 7 ps 1.5";
  mark.x = {p0.x_m};
  mark.y = {p0.y_m};
  xy.series.push_back(std::move(mark));
  return {xy, dist};
}

plot::Panel costPanel(const TuneResult& result) {
  auto p = panel("Best cost vs evaluation (" + result.algorithm + (result.cancelled ? ", cancelled" : "") + ")",
                 "evaluation", "best cost so far (lower is better)");
  auto s = series("best cost", "#1f77b4");
  for (std::size_t i = 0; i < result.best_cost_history.size(); ++i) {
    s.x.push_back(static_cast<double>(i + 1));
    s.y.push_back(result.best_cost_history[i]);
  }
  const double n = std::max<double>(1.0, static_cast<double>(result.best_cost_history.size()));
  auto initial = series("initial gains: " + fmtOrNotConverged(result.initial_eval.cost, 3), "#7f7f7f", 1, true);
  initial.x = {1.0, n};
  initial.y = {result.initial_eval.cost, result.initial_eval.cost};
  auto best = series("best: " + fmtOrNotConverged(result.best_eval.cost, 3), "#2ca02c", 1, true);
  best.x = {1.0, n};
  best.y = {result.best_eval.cost, result.best_eval.cost};
  // From 0, with room above the highest line for the key; a far worse start is clipped so that the descent
  // stays readable.
  double lo = std::numeric_limits<double>::infinity(), hi = 0;
  for (const double v : s.y)
    if (std::isfinite(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  if (std::isfinite(result.initial_eval.cost)) hi = std::max(hi, result.initial_eval.cost);
  if (std::isfinite(lo) && lo > 0 && hi > 10 * lo) {
    hi = 5 * lo;
    p.title += "; y axis clipped, the start is off the scale";
  }
  if (hi > 0) p.yrange = "[0:" + fmtG(hi * 1.3) + "]";
  p.series.push_back(std::move(s));
  p.series.push_back(std::move(initial));
  p.series.push_back(std::move(best));
  return p;
}

// ---------------------------------------------------------------- files

std::string csvName(const std::string& label) {
  std::string out;
  for (const char c : label) out += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return out;
}

std::string tracesCsv(const Comparison& c) {
  std::ostringstream os;
  os.precision(9);
  os << "t_s,ref_x_m,ref_y_m";
  for (const auto& row : c.rows) {
    const std::string n = csvName(row.label);
    os << "," << n << "_x_m," << n << "_y_m," << n << "_pos_err_m," << n << "_ang_err_rad";
  }
  os << "\n";
  std::size_t n = 0;
  for (const auto& row : c.rows) n = std::max(n, row.trace.samples.size());
  for (std::size_t k = 0; k < n; ++k) {
    const sim::ClosedLoopSample* first = nullptr;
    for (const auto& row : c.rows)
      if (k < row.trace.samples.size()) {
        first = &row.trace.samples[k];
        break;
      }
    os << first->t_s << "," << first->ref.x_m << "," << first->ref.y_m;
    for (const auto& row : c.rows) {
      if (k < row.trace.samples.size()) {
        const auto& s = row.trace.samples[k];
        os << "," << s.pose.x_m << "," << s.pose.y_m << "," << s.pos_err_m << "," << s.ang_err_rad;
      } else {
        os << ",,,,";
      }
    }
    os << "\n";
  }
  return os.str();
}

void writeText(const fs::path& path, const std::string& text, SessionFiles& out) {
  if (const std::string err = writeFileAtomically(path.string(), text); !err.empty()) throw std::runtime_error(err);
  out.files.push_back(path.string());
}

std::pair<double, double> boundsOf(const TuneSetup& setup, const std::string& name) {
  const auto it = setup.bounds.find(name);
  return it != setup.bounds.end() ? it->second : defaultTuneBounds(name);
}

int scenarioCount(const TuneSetup& s) { return std::max(1, s.plant_variations) * std::max(1, s.seeds); }

std::string describeScenarios(const TuneSetup& s, int count) {
  std::ostringstream os;
  os << count << " = " << s.plant_variations << " plant variation(s) x " << s.seeds << " noise seed(s)";
  if (s.plant_variations > 1)
    os << "; variations spread around the plant by +-" << fmtG(s.gain_spread * 100) << " % gain, +-"
       << fmtG(s.tau_spread * 100) << " % time constant, +0 to " << fmtG(s.dead_spread_s) << " s more dead time";
  return os.str();
}

std::string mdCell(const std::string& s) {
  std::string out;
  for (const char c : s) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

bool isTuned(const TuneSetup& s, const std::string& name) {
  return std::find(s.params.begin(), s.params.end(), name) != s.params.end();
}

}  // namespace

// ---------------------------------------------------------------- API

std::string plantJson(const control::PlantModel& p) {
  return Json{{"left", wheelJson(p.left)}, {"right", wheelJson(p.right)}}.dump();
}

Comparison compareControllers(const Tuner& tuner, const std::vector<ControllerCase>& cases) {
  Comparison c;
  c.reference = tuner.setup().reference.describe();
  c.plant_description = describePlant(tuner.setup().plant);
  for (const auto& k : cases) {
    ComparisonRow row;
    row.label = k.label;
    row.wheel_control = k.wheel_control;
    row.gains = k.gains;
    row.eval = tuner.evaluate(k.gains, k.wheel_control);
    row.trace = tuner.trace(k.gains, k.wheel_control, 1);
    c.rows.push_back(std::move(row));
  }
  return c;
}

std::string comparisonTable(const Comparison& c) {
  std::size_t w0 = 0;
  for (const auto& r : kRows) w0 = std::max(w0, std::string(r.label).size());
  for (const auto& r : kRobustRows) w0 = std::max(w0, std::string(r.label).size());
  std::vector<std::size_t> wc;
  for (const auto& row : c.rows) wc.push_back(std::max<std::size_t>(12, row.label.size()));
  const int scenarios = c.rows.empty() ? 0 : c.rows.front().eval.scenarios;

  std::ostringstream os;
  const auto line = [&](const std::string& head, const auto& cell) {
    std::string l = head;
    l.resize(w0, ' ');
    for (std::size_t i = 0; i < c.rows.size(); ++i) {
      std::string v = cell(i);
      l += "  " + std::string(wc[i] > v.size() ? wc[i] - v.size() : 0, ' ') + v;
    }
    while (!l.empty() && l.back() == ' ') l.pop_back();
    os << l << "\n";
  };
  os << "Reference: " << c.reference << "\nPlant: " << c.plant_description << "\n";
  line("metric", [&](std::size_t i) { return c.rows[i].label; });
  os << "-- the plant tuned for, noise seed 1 --\n";
  for (const auto& r : kRows) line(r.label, [&](std::size_t i) { return fmtOrNotConverged(r.value(c.rows[i]), r.decimals); });
  os << "-- over " << scenarios << " scenario(s) (plant variations x noise seeds) --\n";
  for (const auto& r : kRobustRows)
    line(r.label, [&](std::size_t i) { return fmtOrNotConverged(r.value(c.rows[i]), r.decimals); });
  return os.str();
}

namespace {

/// The plots drawn: file, what it shows.
using Drawn = std::vector<std::pair<std::string, std::string>>;

/// Tuned gains, with the fuzzy system they belong to: gains_tuned.yaml and .fis.
void writeTunedGains(const fs::path& d, const TuneSetup& setup, const TuneResult& result, const Comparison& c,
                     const fuzzy::Fis& fis, SessionFiles& out) {
  const fs::path yaml = d / "gains_tuned.yaml";
  std::ostringstream comment;
  comment << "Tracking gains tuned by pc_server's tuner (docs/tuning.md).\n"
          << "Reference: " << c.reference << "\nPlant: " << c.plant_description << "\n"
          << "Tuned: ";
  for (std::size_t i = 0; i < setup.params.size(); ++i) comment << (i ? ", " : "") << setup.params[i];
  comment << "; cost " << fmtG(result.initial_eval.cost) << " -> " << fmtG(result.best_eval.cost) << " after "
          << result.evals << " evaluations (" << result.algorithm << (result.cancelled ? ", cancelled" : "") << ")";
  config::exportGains(result.best, fis, yaml.string(), comment.str());
  out.files.push_back((d / "gains_tuned.fis").string());
  out.files.push_back(yaml.string());
}

/// The session's plots; a failure keeps the script with its data and says why (a note).
Drawn drawSessionPlots(const fs::path& d, const TuneSetup& setup, const TuneResult& result, const Comparison& c,
                       SessionFiles& out) {
  Drawn drawn;
  std::error_code ec;
  const auto draw = [&](const std::string& file, const std::vector<plot::Panel>& panels, const std::string& what,
                        int width_px, int height_px) {
    const std::string png = (d / file).string();
    const std::string err = plot::renderPng(png, panels, width_px, height_px);
    if (err.empty()) {
      out.files.push_back(png);
      drawn.emplace_back(file, what);
      return;
    }
    fs::remove(png, ec);
    std::string note = file + " not drawn: " + err;
    std::replace(note.begin(), note.end(), '\n', ' ');
    while (!note.empty() && note.back() == ' ') note.pop_back();
    if (fs::exists(png + ".gp")) {
      out.files.push_back(png + ".gp");
      note += " (the data and gnuplot script are in " + file + ".gp: `gnuplot " + file + ".gp` draws it)";
    }
    out.notes.push_back(note);
  };
  if (!c.rows.empty()) {
    draw("fig20_position_error.png", {errorPanel(c, true)},
         "position error vs time, one curve per controller (as the paper's Fig 20a)", 1000, 480);
    draw("fig20_angle_error.png", {errorPanel(c, false)},
         "angle error vs time, one curve per controller (as the paper's Fig 20b)", 1000, 480);
    draw("trajectory.png", trajectoryPanels(c, setup.reference),
         "reference and each controller's x-y path, and their distance from the reference path", 1000, 560);
  } else {
    out.notes.push_back("no controllers compared: no error or trajectory plots");
  }
  if (!result.best_cost_history.empty())
    draw("cost_history.png", {costPanel(result)}, "best cost after each evaluation", 1000, 450);
  else
    out.notes.push_back("cost_history.png not drawn: no evaluations");
  return drawn;
}

/// results.json: the session's figures, machine-readable.
std::string sessionResultsJson(const TuneSetup& setup, const TuneResult& result, const Comparison& c, int scenarios,
                               const Drawn& drawn, const std::vector<std::string>& notes) {
  Json j;
  j["reference"] = c.reference;
  j["plant"] = {{"left", wheelJson(setup.plant.left)},
                {"right", wheelJson(setup.plant.right)},
                {"description", c.plant_description}};
  Json params = Json::array();
  for (const auto& name : setup.params) {
    const auto [lo, hi] = boundsOf(setup, name);
    params.push_back({{"name", name},
                      {"lower", lo},
                      {"upper", hi},
                      {"initial", numberOrNull(control::gainValue(result.initial, name))},
                      {"best", numberOrNull(control::gainValue(result.best, name))}});
  }
  j["params"] = params;
  const auto& w = setup.weights;
  j["cost_weights"] = {{"max_pos", w.max_pos},         {"rms_pos", w.rms_pos}, {"max_ang", w.max_ang},
                       {"rms_ang", w.rms_ang},         {"convergence", w.convergence},
                       {"effort", w.effort},           {"saturation", w.saturation}};
  j["scenarios"] = {{"count", scenarios},
                    {"plant_variations", setup.plant_variations},
                    {"seeds", setup.seeds},
                    {"gain_spread", setup.gain_spread},
                    {"tau_spread", setup.tau_spread},
                    {"dead_spread_s", setup.dead_spread_s},
                    {"seed", setup.seed}};
  j["algorithm"] = result.algorithm;
  j["max_evals"] = setup.max_evals;
  j["global_fraction"] = setup.global_fraction;
  j["evals"] = result.evals;
  j["wall_s"] = result.wall_s;
  j["cancelled"] = result.cancelled;
  j["initial"] = {{"cost", numberOrNull(result.initial_eval.cost)}, {"gains", gainsObject(result.initial)}};
  j["best"] = {{"cost", numberOrNull(result.best_eval.cost)}, {"gains", gainsObject(result.best)}};
  Json rows = Json::array();
  for (const auto& row : c.rows) {
    Json r;
    r["label"] = row.label;
    r["controller"] = control::toString(row.wheel_control);
    r["gains"] = gainsObject(row.gains);
    r["cost"] = numberOrNull(row.eval.cost);
    r["scenarios"] = row.eval.scenarios;
    Json table_row;
    for (const auto& m : kRows) table_row[m.key] = numberOrNull(m.value(row));  // null: not converged
    for (const auto& m : kRobustRows) table_row[m.key] = numberOrNull(m.value(row));
    r["table"] = table_row;
    r["nominal_trace"] = metricsJson(row.trace.metrics);
    r["mean"] = metricsJson(row.eval.mean);
    r["worst"] = metricsJson(row.eval.worst);
    rows.push_back(std::move(r));
  }
  j["comparison"] = rows;
  j["convergence_bands"] = {{"position_m", kLoopDefaults.settle_position_m},
                            {"angle_rad", kLoopDefaults.settle_angle_rad}};
  Json hist = Json::array();
  for (const double v : result.best_cost_history) hist.push_back(numberOrNull(v));
  j["best_cost_history"] = hist;
  j["plots"] = Json::array();
  for (const auto& [file, what] : drawn) j["plots"].push_back(file);
  j["notes"] = notes;
  return j.dump(2) + "\n";
}

/// summary.md: the session for people.
std::string sessionSummaryMd(const TuneSetup& setup, const TuneResult& result, const Comparison& c, int scenarios,
                             const std::string& table, const Drawn& drawn, const std::vector<std::string>& notes) {
  std::ostringstream md;
  md << "# Tuning session\n\n## Set-up\n\n";
  md << "- Reference: " << c.reference << " (start (0, 0, 0))\n";
  md << "- Plant tuned for: left wheel " << describeWheel(setup.plant.left) << "; right wheel "
     << describeWheel(setup.plant.right) << "\n";
  md << "- Scenarios per evaluation: " << describeScenarios(setup, scenarios) << "; seed " << setup.seed << "\n";
  md << "- Algorithm: " << (result.algorithm.empty() ? "-" : result.algorithm) << "; evaluations: " << result.evals
     << " of at most " << setup.max_evals << " (global share " << fmtG(setup.global_fraction) << "); wall time "
     << fmtOrNotConverged(result.wall_s, 1) << " s; " << (result.cancelled ? "**cancelled** (best so far kept)" : "not cancelled")
     << "\n";
  md << "- Cost: " << fmtG(result.initial_eval.cost) << " (initial gains) -> " << fmtG(result.best_eval.cost)
     << " (best)";
  if (result.initial_eval.cost > 0 && std::isfinite(result.initial_eval.cost))
    md << ", " << fmtOrNotConverged(100.0 * (result.initial_eval.cost - result.best_eval.cost) / result.initial_eval.cost, 1)
       << " % lower";
  md << "\n\n";

  md << "### Parameters and bounds\n\n| parameter | lower | upper | initial | best |\n|---|---|---|---|---|\n";
  for (const auto& name : setup.params) {
    const auto [lo, hi] = boundsOf(setup, name);
    md << "| " << name << " | " << fmtG(lo) << " | " << fmtG(hi) << " | "
       << fmtG(control::gainValue(result.initial, name)) << " | " << fmtG(control::gainValue(result.best, name))
       << " |\n";
  }
  const auto& w = setup.weights;
  md << "\n### Cost weights\n\nEach term is normalised by its scale (pc_server/tuning/tuner.hpp `CostWeights`); "
        "the cost of an evaluation is the mean over the scenarios plus the worst one.\n\n"
        "| term | scale | weight |\n|---|---|---|\n"
     << "| max position error | 0.05 m | " << fmtG(w.max_pos) << " |\n"
     << "| RMS position error | 0.01 m | " << fmtG(w.rms_pos) << " |\n"
     << "| max angle error | 0.05 rad | " << fmtG(w.max_ang) << " |\n"
     << "| RMS angle error | 0.01 rad | " << fmtG(w.rms_ang) << " |\n"
     << "| convergence (position + angle) / 2 | 10 s | " << fmtG(w.convergence) << " |\n"
     << "| max(0, effort / the reference's own effort - 1) | 1 | " << fmtG(w.effort) << " |\n"
     << "| fraction of the run saturated | 0.1 | " << fmtG(w.saturation) << " |\n"
     << "\nPlus 50 for each of position and angle still outside its band at the end of a run; a diverged run "
        "(max position error over 1 m, or a non-finite figure) costs 10^4 or more.\n";

  md << "\n## Comparison\n\nNominal rows: the plant above, noise seed 1 (the plotted runs). Convergence: the time "
        "after which the error stays within the band (position "
     << fmtG(kLoopDefaults.settle_position_m) << " m, angle " << fmtG(kLoopDefaults.settle_angle_rad)
     << " rad) to the end; `not conv.` if it ends outside. Effort = integral of (u_l^2 + u_r^2) dt; saturation "
        "time = time with a wheel command at the limit.\n\n```\n"
     << table << "```\n\n";

  md << "## Gains\n\n| gain | initial | best | |\n|---|---|---|---|\n";
  for (const char* name : control::kGainNames) {
    const double a = control::gainValue(result.initial, name), b = control::gainValue(result.best, name);
    md << "| " << name << " | " << fmtG(a) << " | " << fmtG(b) << " | "
       << (isTuned(setup, name) ? (a != b ? "tuned, changed" : "tuned") : "fixed") << " |\n";
  }
  md << "\nThe best gains are in [gains_tuned.yaml](gains_tuned.yaml) (with the fuzzy system "
        "[gains_tuned.fis](gains_tuned.fis)); every figure above is in [results.json](results.json), the "
        "plotted runs sample by sample in [traces.csv](traces.csv).\n\n";

  md << "## Plots\n\n";
  if (drawn.empty()) md << "No plots were drawn.\n";
  for (const auto& [file, what] : drawn) md << "- [" << file << "](" << file << "): " << what << "\n";
  for (const auto& n : notes) md << "- " << mdCell(n) << "\n";
  md << "\n";
  for (const auto& [file, what] : drawn) md << "![" << file << "](" << file << ")\n\n";
  return md.str();
}

}  // namespace

SessionFiles writeTuningSession(const std::string& dir, const TuneSetup& setup, const TuneResult& result,
                                const Comparison& c, const fuzzy::Fis& fis) {
  SessionFiles out;
  out.dir = dir;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error("cannot create " + dir + ": " + ec.message());
  const fs::path d(dir);
  writeTunedGains(d, setup, result, c, fis, out);
  writeText(d / "traces.csv", tracesCsv(c), out);
  const Drawn drawn = drawSessionPlots(d, setup, result, c, out);
  const std::string table = comparisonTable(c);
  const int scenarios = result.best_eval.scenarios > 0 ? result.best_eval.scenarios : scenarioCount(setup);
  writeText(d / "results.json", sessionResultsJson(setup, result, c, scenarios, drawn, out.notes), out);
  writeText(d / "summary.md", sessionSummaryMd(setup, result, c, scenarios, table, drawn, out.notes), out);
  return out;
}

}  // namespace inspect::tuning
