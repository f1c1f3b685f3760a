// Plant identification (method in plant_id.hpp), the run reader and the plant file.
#include "pc_server/tuning/plant_id.hpp"

#include "shared/util/number_text.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <limits>
#include <set>
#include <sstream>

#include <nlopt.hpp>

#include "inspect_robot/v1/link.pb.h"
#include "shared/config/config_node.hpp"
#include "shared/record/mcap_reader.hpp"

namespace inspect::tuning {
using util::significant;
namespace {

constexpr std::size_t kMinSamples = 50;        // 1 s of 50 Hz telemetry
constexpr std::size_t kMinStretchPoints = 3;   // shorter stretches between gaps are dropped
constexpr double kDeadTimeStep_s = 0.005;      // start-point grid
constexpr double kMinGain = 0.2, kMaxGain = 5.0;     // control::validatePlant's ranges
constexpr double kMinTau_s = 0.001, kMaxTau_s = 5.0;
constexpr double kFitWarnPercent = 80.0;
constexpr double kGainRatioWarn = 1.2;
constexpr double kMinExcitedTime_s = 2.0;
constexpr double kMaxSaturationStart = 0.9;    // saturation starts below this x the largest command
constexpr double kSaturationGainNeeded = 0.9;  // a saturation is kept when the squared error drops below this x
constexpr double kSaturationBelow = 0.95;      // ... and it lies below this x the largest command
constexpr int kPlateauWindow = 5;              // samples averaged for the plateau (0.1 s at 50 Hz)


// One stretch between gaps on the uniform grid.
struct Stretch {
  std::vector<double> u, y;
};

struct Grid {
  double h_s = 0.0;
  std::vector<Stretch> stretches;
  std::size_t points = 0;
  std::size_t gaps = 0;
  double max_abs_command = 0.0;
  double excited_s = 0.0;  // grid time with |u| above min_excitation
};

double median(std::vector<double> v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

[[noreturn]] void fail(const std::string& wheel, const std::string& what) {
  throw IdentifyError(wheel + " wheel: " + what);
}

Grid prepare(const std::string& wheel, const WheelSeries& s, const IdentifyOptions& o) {
  const auto& t = s.t_s;
  const auto& u = s.command_rad_s;
  const auto& y = s.measured_rad_s;
  if (t.size() != u.size() || t.size() != y.size())
    fail(wheel, "t_s, command_rad_s and measured_rad_s have different lengths (" + std::to_string(t.size()) + ", " +
                    std::to_string(u.size()) + ", " + std::to_string(y.size()) + ")");
  if (t.size() < kMinSamples)
    fail(wheel, "too few samples (" + std::to_string(t.size()) + "; at least " + std::to_string(kMinSamples) +
                    " needed)");
  for (std::size_t i = 0; i < t.size(); ++i) {
    const char* bad = !std::isfinite(t[i]) ? "t_s" : !std::isfinite(u[i]) ? "command_rad_s"
                                                   : !std::isfinite(y[i]) ? "measured_rad_s" : nullptr;
    if (bad) fail(wheel, std::string(bad) + " of sample " + std::to_string(i) + " is not finite");
    if (i > 0 && t[i] < t[i - 1])
      fail(wheel, "time goes backwards at sample " + std::to_string(i) + " (" + significant(t[i], 9) + " s after " +
                      significant(t[i - 1], 9) + " s)");
    if (i > 0 && t[i] == t[i - 1])
      fail(wheel, "time repeats at sample " + std::to_string(i) + " (" + significant(t[i], 9) + " s)");
  }
  Grid g;
  for (double v : u) g.max_abs_command = std::max(g.max_abs_command, std::abs(v));
  if (!(g.max_abs_command > o.min_excitation_rad_s))
    fail(wheel, "no excitation: the command never exceeds " + significant(o.min_excitation_rad_s, 4) + " rad/s");
  const double y_lo = *std::min_element(y.begin(), y.end()), y_hi = *std::max_element(y.begin(), y.end());
  if (y_hi - y_lo < 1e-9)
    fail(wheel, "the measured speed never changes (" + significant(y_lo, 4) + " rad/s): did the wheel move?");

  std::vector<double> dt(t.size() - 1);
  for (std::size_t i = 1; i < t.size(); ++i) dt[i - 1] = t[i] - t[i - 1];
  g.h_s = median(dt);
  if (g.h_s > o.max_gap_s)
    fail(wheel, "the median sample interval (" + significant(g.h_s, 4) + " s) is longer than max_gap_s (" + significant(o.max_gap_s, 4) +
                    " s)");

  // Split at gaps, then interpolate each stretch onto its own grid t0 + j h.
  std::size_t begin = 0;
  for (std::size_t i = 1; i <= t.size(); ++i) {
    if (i < t.size() && t[i] - t[i - 1] <= o.max_gap_s) continue;
    if (i < t.size()) ++g.gaps;
    const std::size_t end = i;  // [begin, end)
    const double t0 = t[begin];
    const auto n = static_cast<std::size_t>(std::floor((t[end - 1] - t0) / g.h_s + 1e-9)) + 1;
    if (n >= kMinStretchPoints) {
      Stretch st;
      st.u.reserve(n);
      st.y.reserve(n);
      std::size_t k = begin;
      for (std::size_t j = 0; j < n; ++j) {
        const double tj = t0 + static_cast<double>(j) * g.h_s;
        while (k + 2 < end && t[k + 1] <= tj) ++k;
        const double f = k + 1 < end ? std::clamp((tj - t[k]) / (t[k + 1] - t[k]), 0.0, 1.0) : 0.0;
        const std::size_t k1 = std::min(k + 1, end - 1);
        st.u.push_back(u[k] + f * (u[k1] - u[k]));
        st.y.push_back(y[k] + f * (y[k1] - y[k]));
        if (std::abs(st.u.back()) > o.min_excitation_rad_s) g.excited_s += g.h_s;
      }
      g.points += n;
      g.stretches.push_back(std::move(st));
    }
    begin = i;
  }
  if (g.points < kMinSamples)
    fail(wheel, "too few samples between gaps longer than " + significant(o.max_gap_s, 4) + " s (" + std::to_string(g.points) +
                    " on the grid; at least " + std::to_string(kMinSamples) + " needed)");
  return g;
}

struct Params {
  double gain = 1.0, tau_s = 0.2, dead_s = 0.0, sat_rad_s = 5.0;
};

// The delayed command at grid point j: u(t_j - dead), linear between samples,
// the first sample before the stretch starts.
double delayed(const std::vector<double>& u, std::size_t j, double shift) {
  const double pos = static_cast<double>(j) - shift;
  if (pos <= 0.0) return u[0];
  const auto m = static_cast<std::size_t>(pos);
  const double f = pos - static_cast<double>(m);
  return m + 1 < u.size() ? u[m] + f * (u[m + 1] - u[m]) : u[m];
}

// Simulates the model over every stretch from its first measured value and
// returns the sum of squared output errors; fills yhat (all stretches in a
// row) when given.
double simulate(const Grid& g, const Params& p, std::vector<double>* yhat = nullptr) {
  const double h = g.h_s;
  const double a = std::exp(-h / p.tau_s);
  // Exact step of tau w' = K u - w with u linear from ua to ub over h:
  // w+ = a w + K (c0 ua + c1 ub).
  const double r = p.tau_s / h * (1.0 - a);
  const double c0 = r - a, c1 = 1.0 - r;
  const double shift = p.dead_s / h;
  const auto sat = [&](double v) { return std::clamp(v, -p.sat_rad_s, p.sat_rad_s); };
  double sse = 0.0;
  if (yhat) yhat->clear();
  for (const auto& s : g.stretches) {
    double w = s.y[0];
    double ua = sat(delayed(s.u, 0, shift));
    if (yhat) yhat->push_back(w);
    for (std::size_t j = 1; j < s.y.size(); ++j) {
      const double ub = sat(delayed(s.u, j, shift));
      w = a * w + p.gain * (c0 * ua + c1 * ub);
      ua = ub;
      const double e = s.y[j] - w;
      sse += e * e;
      if (yhat) yhat->push_back(w);
    }
  }
  return sse;
}

// First-order ARX y[k+1] = a y[k] + b (ud[k] + ud[k+1]) / 2 by least squares
// for one dead time; false when it does not describe a stable lag. The gain
// keeps its sign (a reversed wheel is refused by the caller).
bool arxStart(const Grid& g, double dead_s, double sat_rad_s, Params& out) {
  double syy = 0, syu = 0, suu = 0, sy1y = 0, sy1u = 0;
  const double shift = dead_s / g.h_s;
  for (const auto& s : g.stretches)
    for (std::size_t j = 0; j + 1 < s.y.size(); ++j) {
      const double um = 0.5 * (std::clamp(delayed(s.u, j, shift), -sat_rad_s, sat_rad_s) +
                               std::clamp(delayed(s.u, j + 1, shift), -sat_rad_s, sat_rad_s));
      syy += s.y[j] * s.y[j];
      syu += s.y[j] * um;
      suu += um * um;
      sy1y += s.y[j + 1] * s.y[j];
      sy1u += s.y[j + 1] * um;
    }
  const double det = syy * suu - syu * syu;
  if (!(std::abs(det) > 1e-12 * std::max(1.0, syy * suu))) return false;
  double a = (sy1y * suu - syu * sy1u) / det;
  const double b = (syy * sy1u - syu * sy1y) / det;
  if (!std::isfinite(a) || !std::isfinite(b)) return false;
  a = std::clamp(a, std::exp(-g.h_s / kMinTau_s), std::exp(-g.h_s / kMaxTau_s));
  const double gain = b / (1.0 - a);
  if (!std::isfinite(gain) || gain == 0.0) return false;
  out.gain = std::copysign(std::clamp(std::abs(gain), kMinGain, kMaxGain), gain);
  out.tau_s = std::clamp(-g.h_s / std::log(a), kMinTau_s, kMaxTau_s);
  out.dead_s = dead_s;
  out.sat_rad_s = sat_rad_s;
  return true;
}

// The parameters NLopt moves: gain, tau, dead time (unless max_dead_time_s
// is 0) and the saturation (when asked); the others stay at `base`.
struct Problem {
  const Grid* grid = nullptr;
  Params base;
  std::vector<double Params::*> free;
  double best = std::numeric_limits<double>::infinity();
  Params best_p;
};

Params unpack(const Problem& pr, const double* x) {
  Params p = pr.base;
  for (std::size_t i = 0; i < pr.free.size(); ++i) p.*pr.free[i] = x[i];
  return p;
}

double objective(unsigned /*n*/, const double* x, double* /*grad*/, void* data) {
  auto& pr = *static_cast<Problem*>(data);
  const Params p = unpack(pr, x);
  const double f = simulate(*pr.grid, p);
  if (f < pr.best) {
    pr.best = f;
    pr.best_p = p;
  }
  return f;
}

// Output-error refinement from `start` with LN_BOBYQA; returns the best
// parameters seen and their squared error.
Params refine(const Grid& g, const Params& start, bool with_saturation, double sat_lo, double sat_hi,
              double max_dead_s, double& sse) {
  Problem pr;
  pr.grid = &g;
  pr.base = start;
  std::vector<double> lo, hi, x, step;
  const auto add = [&](double Params::*m, double l, double u, double dx) {
    pr.free.push_back(m);
    lo.push_back(l);
    hi.push_back(u);
    x.push_back(std::clamp(start.*m, l, u));
    step.push_back(std::min(dx, 0.25 * (u - l)));
  };
  add(&Params::gain, kMinGain, kMaxGain, 0.05 * start.gain);
  add(&Params::tau_s, kMinTau_s, kMaxTau_s, 0.1 * start.tau_s);
  if (max_dead_s > 0.0) add(&Params::dead_s, 0.0, max_dead_s, 0.5 * g.h_s);
  if (with_saturation) add(&Params::sat_rad_s, sat_lo, sat_hi, 0.05 * start.sat_rad_s);
  nlopt::opt opt(nlopt::LN_BOBYQA, static_cast<unsigned>(x.size()));
  opt.set_lower_bounds(lo);
  opt.set_upper_bounds(hi);
  opt.set_initial_step(step);
  opt.set_min_objective(objective, &pr);
  opt.set_xtol_rel(1e-6);
  opt.set_ftol_rel(1e-12);
  opt.set_maxeval(600);
  double f = 0.0;
  try {
    opt.optimize(x, f);
  } catch (const std::exception&) {
    // Round-off limits and the like: the best point seen stands.
  }
  if (!std::isfinite(pr.best)) {
    sse = simulate(g, start);
    return start;
  }
  sse = pr.best;
  return pr.best_p;
}

// The largest |measured| speed held over kPlateauWindow samples.
double plateau(const Grid& g) {
  double best = 0.0;
  for (const auto& s : g.stretches) {
    if (s.y.size() < static_cast<std::size_t>(kPlateauWindow)) continue;
    double sum = 0.0;
    for (std::size_t j = 0; j < s.y.size(); ++j) {
      sum += s.y[j];
      if (j >= static_cast<std::size_t>(kPlateauWindow)) sum -= s.y[j - kPlateauWindow];
      if (j + 1 >= static_cast<std::size_t>(kPlateauWindow)) best = std::max(best, std::abs(sum) / kPlateauWindow);
    }
  }
  return best;
}

WheelFit fitWheel(const std::string& wheel, const Grid& g, const IdentifyOptions& o,
                  std::vector<std::string>& warnings) {
  const double sat_nominal = o.nominal_saturation_rad_s;
  // Start point: ARX at each dead time, judged by its simulated error.
  Params start;
  double start_sse = std::numeric_limits<double>::infinity();
  const int dead_steps = static_cast<int>(std::floor(o.max_dead_time_s / kDeadTimeStep_s + 1e-9));
  for (int i = 0; i <= dead_steps; ++i) {
    Params p;
    if (!arxStart(g, i * kDeadTimeStep_s, sat_nominal, p)) continue;
    const double sse = simulate(g, p);
    if (sse < start_sse) {
      start_sse = sse;
      start = p;
    }
  }
  if (!std::isfinite(start_sse) || start.gain < 0.0)
    fail(wheel, "the measured speed does not follow the command with a positive gain (wheel or its sign reversed?)");

  double sse = 0.0;
  Params best = refine(g, start, false, 0.0, 0.0, o.max_dead_time_s, sse);
  WheelFit fit;
  // Saturation: refit with it as a fourth parameter, started from the
  // plateau (largest held |measured| / gain) and from fractions of the
  // largest command: a saturated run biases the 3-parameter gain low, which
  // makes the plateau alone look unsaturated.
  const double reachable = std::min(g.max_abs_command, sat_nominal);
  const double lo = std::min(o.min_excitation_rad_s, 0.5 * reachable);
  Params sat_best;
  double sat_sse = std::numeric_limits<double>::infinity();
  for (const double s0 : {plateau(g) / best.gain, 0.85 * reachable, 0.7 * reachable, 0.5 * reachable}) {
    if (!(s0 < kMaxSaturationStart * reachable)) continue;
    Params from = best;
    from.sat_rad_s = std::max(s0, lo);
    double sse4 = 0.0;
    const Params p4 = refine(g, from, true, lo, reachable, o.max_dead_time_s, sse4);
    if (sse4 < sat_sse) {
      sat_sse = sse4;
      sat_best = p4;
    }
  }
  if (sat_sse < kSaturationGainNeeded * sse && sat_best.sat_rad_s < kSaturationBelow * reachable) {
    best = sat_best;
    sse = sat_sse;
    fit.saturation_observed = true;
  }
  if (!fit.saturation_observed) best.sat_rad_s = sat_nominal;

  std::vector<double> yhat;
  sse = simulate(g, best, &yhat);
  double mean = 0.0;
  for (const auto& s : g.stretches)
    for (double v : s.y) mean += v;
  mean /= static_cast<double>(g.points);
  double spread = 0.0;
  for (const auto& s : g.stretches)
    for (double v : s.y) spread += (v - mean) * (v - mean);
  fit.model = {best.gain, best.tau_s, best.dead_s, best.sat_rad_s};
  fit.samples = g.points;
  fit.rms_error_rad_s = std::sqrt(sse / static_cast<double>(g.points));
  fit.fit_percent = 100.0 * (1.0 - std::sqrt(sse / spread));  // spread > 0: the speed changes (checked)

  if (fit.fit_percent < kFitWarnPercent)
    warnings.push_back(wheel + " wheel: fit " + significant(fit.fit_percent, 3) + " % is below " + significant(kFitWarnPercent, 4) +
                       " %: the model reproduces the run poorly (slip, load changes, a non-linear motor?)");
  if (g.excited_s < kMinExcitedTime_s)
    warnings.push_back(wheel + " wheel: barely excited (" + significant(g.excited_s, 3) + " s with |command| above " +
                       significant(o.min_excitation_rad_s, 4) + " rad/s; the figures are uncertain)");
  if (o.max_dead_time_s > 0.0 && best.dead_s > o.max_dead_time_s - 0.5 * kDeadTimeStep_s)
    warnings.push_back(wheel + " wheel: the dead time is at the search limit (" + significant(o.max_dead_time_s, 4) +
                       " s): raise max_dead_time_s or check the recording");
  if (g.gaps > 0)
    warnings.push_back(wheel + " wheel: " + std::to_string(g.gaps) + " gap(s) longer than " + significant(o.max_gap_s, 4) +
                       " s (link loss?); each stretch is simulated from its first sample");
  return fit;
}

void checkOptions(const IdentifyOptions& o) {
  if (!std::isfinite(o.max_dead_time_s) || o.max_dead_time_s < 0.0 || o.max_dead_time_s > 1.0)
    throw IdentifyError("options: max_dead_time_s must be in [0, 1]");
  if (!std::isfinite(o.nominal_saturation_rad_s) || o.nominal_saturation_rad_s <= 0.0 ||
      o.nominal_saturation_rad_s > 100.0)
    throw IdentifyError("options: nominal_saturation_rad_s must be in (0, 100]");
  if (!std::isfinite(o.min_excitation_rad_s) || o.min_excitation_rad_s <= 0.0)
    throw IdentifyError("options: min_excitation_rad_s must be positive");
  if (!std::isfinite(o.max_gap_s) || o.max_gap_s <= 0.0) throw IdentifyError("options: max_gap_s must be positive");
}

// A YAML double-quoted scalar.
std::string yamlQuote(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\x%02x", static_cast<unsigned>(static_cast<unsigned char>(c)));
          out += buf;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

// A comment line: no line breaks inside.
std::string oneLine(std::string s) {
  std::replace_if(s.begin(), s.end(), [](char c) { return c == '\n' || c == '\r'; }, ' ');
  return s;
}

}  // namespace

PlantFit identifyPlant(const WheelSeries& left, const WheelSeries& right, const IdentifyOptions& options) {
  checkOptions(options);
  const Grid gl = prepare("left", left, options);
  const Grid gr = prepare("right", right, options);
  PlantFit out;
  out.left = fitWheel("left", gl, options, out.warnings);
  out.right = fitWheel("right", gr, options, out.warnings);
  out.model = {out.left.model, out.right.model};
  out.duration_s = std::max(left.t_s.back() - left.t_s.front(), right.t_s.back() - right.t_s.front());
  out.sample_period_s = std::max(gl.h_s, gr.h_s);
  const double gmax = std::max(out.left.model.gain, out.right.model.gain);
  const double gmin = std::min(out.left.model.gain, out.right.model.gain);
  if (gmax > kGainRatioWarn * gmin)
    out.warnings.push_back("the wheels' gains differ by more than 20 % (left " + significant(out.left.model.gain, 4) + ", right " +
                           significant(out.right.model.gain, 4) + "): a worn or dragging motor?");
  return out;
}

RunWheelData readRunWheelSeries(const std::string& mcap_path) {
  const auto reader = record::McapReader::open(mcap_path);  // names the file on errors
  std::set<uint16_t> ids;
  std::string topics;
  const std::string type = v1::Telemetry::descriptor()->full_name();
  for (const auto& [id, ch] : reader.channels()) {
    topics += (topics.empty() ? "" : ", ") + ch.topic;
    // "/<robot>/telemetry" (pc_server/scene/topics) or an older run's "/telemetry": no deeper topic.
    if (!ch.topic.ends_with("/telemetry") || std::count(ch.topic.begin(), ch.topic.end(), '/') > 2) continue;
    if (ch.message_encoding != "protobuf" || ch.schema_name != type)
      throw std::runtime_error(mcap_path + ": /telemetry is not " + type + " in protobuf (encoding '" +
                               ch.message_encoding + "', schema '" + ch.schema_name + "')");
    ids.insert(id);
  }
  if (ids.empty())
    throw std::runtime_error(mcap_path + ": no /telemetry channel (channels: " + (topics.empty() ? "none" : topics) +
                             ")");
  RunWheelData out;
  std::string error;
  bool have_first = false;
  uint64_t first_us = 0, last_us = 0;
  bool use_mcu = false;
  v1::Telemetry tm;
  reader.forEach([&](const record::McapMessageView& m) {  // does the robot send its MCU clock?
    if (ids.count(m.channel_id) && tm.ParseFromArray(m.data.data(), static_cast<int>(m.data.size())) &&
        tm.has_mcu_time_us())
      use_mcu = true;
    return !use_mcu;
  });
  reader.forEach([&](const record::McapMessageView& m) {
    if (!ids.count(m.channel_id)) return true;
    ++out.telemetry_messages;
    if (!tm.ParseFromArray(m.data.data(), static_cast<int>(m.data.size()))) {
      error = mcap_path + ": /telemetry message " + std::to_string(m.sequence) + " does not parse as " + type;
      return false;
    }
    // A sample the robot measured nothing for (no sensor frame yet: the wheel
    // speeds left out, link protocol 2) is not a sample.
    if (!tm.has_wheel_left_rad_s() || !tm.has_wheel_right_rad_s()) return true;
    const double vals[4] = {tm.cmd_wheel_left_rad_s(), tm.wheel_left_rad_s(), tm.cmd_wheel_right_rad_s(),
                            tm.wheel_right_rad_s()};
    if (!std::all_of(std::begin(vals), std::end(vals), [](double v) { return std::isfinite(v); })) return true;
    // The sample clock: the MCU's (the time base of the wheel loop and of the
    // simulator at any --rate), else the robot's monotonic clock (older runs).
    if (use_mcu && !tm.has_mcu_time_us()) return true;  // before the robot's first sensor frame
    const uint64_t now_us = use_mcu ? tm.mcu_time_us() : tm.robot_time_us();
    if (have_first && now_us <= last_us) return true;  // a repeat, out of order, or a clock restart
    if (!have_first) first_us = now_us;
    have_first = true;
    last_us = now_us;
    const double t = static_cast<double>(now_us - first_us) * 1e-6;
    out.left.t_s.push_back(t);
    out.left.command_rad_s.push_back(vals[0]);
    out.left.measured_rad_s.push_back(vals[1]);
    out.right.t_s.push_back(t);
    out.right.command_rad_s.push_back(vals[2]);
    out.right.measured_rad_s.push_back(vals[3]);
    ++out.samples_used;
    return true;
  });
  if (!error.empty()) throw std::runtime_error(error);
  if (out.telemetry_messages == 0) throw std::runtime_error(mcap_path + ": the /telemetry channel has no messages");
  return out;
}

std::string plantYaml(const PlantFit& fit, const std::string& source) {
  std::ostringstream os;
  os << std::setprecision(6);
  os << "# Hub-motor plant identified from " << oneLine(source) << "\n"
     << "# Per wheel: w = gain e^(-dead_time s) / (time_constant s + 1) clamp(u, +-saturation)\n"
     << "# (shared/control/plant_model.hpp). The dead time includes robot_client's loop latency:\n"
     << "# this is the plant as the controller sees it. The console's `tune plant=...` reads it\n"
     << "# (loadPlantFile); the plant: section also fits a world file (docs/world-format.md).\n";
  os << "# " << fit.left.samples << " / " << fit.right.samples << " samples (left / right) over "
     << fit.duration_s << " s, resampled at " << fit.sample_period_s * 1e3 << " ms.\n";
  if (fit.warnings.empty()) {
    os << "# No warnings.\n";
  } else {
    os << "# Warnings:\n";
    for (const auto& w : fit.warnings) os << "#   - " << oneLine(w) << "\n";
  }
  os << "source: " << yamlQuote(source) << "\n";
  os << "plant:\n";
  const auto wheel = [&](const char* name, const WheelFit& f) {
    os << "  " << name << ":\n"
       << "    gain: " << f.model.gain << "\n"
       << "    time_constant_s: " << f.model.time_constant_s << "\n"
       << "    dead_time_s: " << f.model.dead_time_s << "\n"
       << "    saturation_rad_s: " << f.model.saturation_rad_s
       << (f.saturation_observed ? "   # reached in the run" : "   # not reached in the run: the nominal limit")
       << "\n";
  };
  wheel("left", fit.left);
  wheel("right", fit.right);
  os << "# How well the model reproduces the run (for people; the tuner ignores it).\n"
     << "fit:\n"
     << "  duration_s: " << fit.duration_s << "\n"
     << "  sample_period_s: " << fit.sample_period_s << "\n";
  const auto figures = [&](const char* name, const WheelFit& f) {
    os << "  " << name << ":\n"
       << "    fit_percent: " << f.fit_percent << "   # 100 (1 - |y - yhat| / |y - mean(y)|), 100 = perfect\n"
       << "    rms_error_rad_s: " << f.rms_error_rad_s << "\n"
       << "    samples: " << f.samples << "\n"
       << "    saturation_observed: " << (f.saturation_observed ? "true" : "false") << "\n";
  };
  figures("left", fit.left);
  figures("right", fit.right);
  return os.str();
}

control::PlantModel loadPlantFile(const std::string& path) {
  const auto root = config::ConfigNode::loadFile(path);
  (void)root.string("source", "");
  const auto plant = root.child("plant");
  const auto wheel = [&](const char* key) {
    const auto n = plant.child(key);
    control::WheelMotorModel m;
    m.gain = n.requireNumber("gain", kMinGain, kMaxGain);
    m.time_constant_s = n.requireNumber("time_constant_s", kMinTau_s, kMaxTau_s);
    m.dead_time_s = n.requireNumber("dead_time_s", 0.0, 1.0);
    m.saturation_rad_s = n.requireNumber("saturation_rad_s", 0.0, 100.0);
    if (!(m.saturation_rad_s > 0.0)) n.fail("saturation_rad_s", "must be in (0, 100]");
    return m;
  };
  const control::PlantModel p{wheel("left"), wheel("right")};
  const auto fit = root.optChild("fit");
  (void)fit.number("duration_s", 0.0, 0.0, 1e9);
  (void)fit.number("sample_period_s", 0.0, 0.0, 1e3);
  for (const char* key : {"left", "right"}) {
    const auto f = fit.optChild(key);
    (void)f.number("fit_percent", 0.0, -1e12, 100.0);
    (void)f.number("rms_error_rad_s", 0.0, 0.0, 1e6);
    (void)f.integer("samples", 0, 0, 1'000'000'000'000L);
    (void)f.boolean("saturation_observed", false);
  }
  root.checkKnown();
  if (const auto e = control::validatePlant(p); !e.empty()) throw config::ConfigError(path + ": plant." + e);
  return p;
}

}  // namespace inspect::tuning
