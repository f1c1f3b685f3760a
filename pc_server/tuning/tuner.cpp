// The fuzzy-PID tuner of pc_server/tuning/tuner.hpp: scenarios, cost, the
// worker pool and the two-phase NLopt search.
#include "pc_server/tuning/tuner.hpp"

#include "shared/util/number_text.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <limits>
#include <map>
#include <mutex>
#include <random>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <nlopt.hpp>

#include "shared/control/trajectory_tracker.hpp"
#include "shared/fuzzy/fis_error.hpp"

namespace inspect::tuning {
using util::significant;

namespace {

using Clock = std::chrono::steady_clock;
using SchedulerPtr = std::shared_ptr<control::FuzzyGainScheduler>;

constexpr double kPosScale_m = 0.05, kRmsPosScale_m = 0.01;
constexpr double kAngScale_rad = 0.05, kRmsAngScale_rad = 0.01;
constexpr double kConvergenceScale_s = 10.0;
constexpr double kSaturationScale = 10.0;
constexpr double kNotConvergedPenalty = 50.0;
constexpr double kDivergedPosition_m = 1.0;
constexpr double kDivergedCost = 1e4;
constexpr double kNonFiniteCost = 2e4;

// ---------------------------------------------------------------- metrics

using MetricField = double sim::ClosedLoopMetrics::*;
constexpr MetricField kMetricFields[] = {
    &sim::ClosedLoopMetrics::max_pos_err_m,     &sim::ClosedLoopMetrics::max_ang_err_rad,
    &sim::ClosedLoopMetrics::rms_pos_err_m,     &sim::ClosedLoopMetrics::rms_ang_err_rad,
    &sim::ClosedLoopMetrics::converge_pos_s,    &sim::ClosedLoopMetrics::converge_ang_s,
    &sim::ClosedLoopMetrics::effort,            &sim::ClosedLoopMetrics::command_variation,
    &sim::ClosedLoopMetrics::saturated_s,       &sim::ClosedLoopMetrics::duration_s,
    &sim::ClosedLoopMetrics::final_pos_err_m};

// ---------------------------------------------------------------- worker pool

/// Persistent worker threads, each with its own fuzzy scheduler (the
/// scheduler keeps per-call output state). run() hands out task indices and
/// waits for all of them; what a task writes is indexed by the task, so the
/// result does not depend on which worker ran it.
class WorkerPool {
 public:
  using Task = std::function<void(int index, const SchedulerPtr& scheduler)>;

  /// Each worker builds its own scheduler (compiling a lookup surface takes a
  /// while); throws what the first failing one threw (fuzzy::FisError).
  WorkerPool(int threads, const fuzzy::Fis& fis, bool use_lookup)
      : scheds_(static_cast<std::size_t>(threads)), errors_(static_cast<std::size_t>(threads)) {
    try {
      for (int i = 0; i < threads; ++i) threads_.emplace_back([this, i, &fis, use_lookup] {
        const auto k = static_cast<std::size_t>(i);
        try {
          scheds_[k] = std::make_shared<control::FuzzyGainScheduler>(fis, use_lookup);
        } catch (...) {
          errors_[k] = std::current_exception();
        }
        {
          std::lock_guard<std::mutex> lk(m_);
          ++done_;
        }
        done_cv_.notify_all();
        loop(i);
      });
    } catch (...) {
      stop();  // a thread could not start (a resource limit): join those that did
      throw;
    }
    std::unique_lock<std::mutex> lk(m_);
    done_cv_.wait(lk, [&] { return done_ == threads; });
    for (const auto& e : errors_)
      if (e) {
        lk.unlock();
        stop();
        std::rethrow_exception(e);
      }
  }
  ~WorkerPool() { stop(); }

  /// Runs task(i, scheduler) for i in [0, count); rethrows the lowest-indexed task's exception.
  void run(int count, const Task& task) {
    std::lock_guard<std::mutex> serial(run_m_);
    std::unique_lock<std::mutex> lk(m_);
    task_ = &task;
    count_ = count;
    next_ = 0;
    done_ = 0;
    errors_.assign(static_cast<std::size_t>(count), nullptr);
    ++generation_;
    work_cv_.notify_all();
    done_cv_.wait(lk, [&] { return done_ == count_; });
    task_ = nullptr;
    for (auto& e : errors_)
      if (e) std::rethrow_exception(e);
  }

 private:
  void loop(int worker) {
    uint64_t seen = 0;
    std::unique_lock<std::mutex> lk(m_);
    for (;;) {
      work_cv_.wait(lk, [&] { return stop_ || (generation_ != seen && next_ < count_); });
      if (stop_) return;
      while (next_ < count_) {
        const int i = next_++;
        const Task* task = task_;
        lk.unlock();
        std::exception_ptr err;
        try {
          (*task)(i, scheds_[static_cast<std::size_t>(worker)]);
        } catch (...) {
          err = std::current_exception();
        }
        lk.lock();
        errors_[static_cast<std::size_t>(i)] = err;
        if (++done_ == count_) done_cv_.notify_all();
      }
      seen = generation_;
    }
  }

  void stop() {
    {
      std::lock_guard<std::mutex> lk(m_);
      stop_ = true;
    }
    work_cv_.notify_all();
    for (auto& t : threads_)
      if (t.joinable()) t.join();
  }

  std::vector<SchedulerPtr> scheds_;
  std::vector<std::thread> threads_;
  std::mutex run_m_;  // one run() at a time
  std::mutex m_;
  std::condition_variable work_cv_, done_cv_;
  const Task* task_ = nullptr;
  int count_ = 0, next_ = 0, done_ = 0;
  uint64_t generation_ = 0;
  bool stop_ = false;
  std::vector<std::exception_ptr> errors_;
};

// ---------------------------------------------------------------- set-up

std::string joinedGainNames() {
  std::string s;
  for (const char* n : control::kGainNames) s += (s.empty() ? "" : ", ") + std::string(n);
  return s;
}

bool isGainName(const std::string& name) {
  return std::any_of(control::kGainNames.begin(), control::kGainNames.end(),
                     [&](const char* n) { return name == n; });
}


nlopt::algorithm globalAlgorithm(const std::string& name) {
  if (name == "GN_CRS2_LM") return nlopt::GN_CRS2_LM;
  if (name == "GN_ISRES") return nlopt::GN_ISRES;
  if (name == "GN_DIRECT_L") return nlopt::GN_DIRECT_L;
  if (name == "GN_ESCH") return nlopt::GN_ESCH;
  throw std::invalid_argument("global_algorithm '" + name + "' is not one of GN_CRS2_LM, GN_ISRES, GN_DIRECT_L, GN_ESCH");
}

nlopt::algorithm localAlgorithm(const std::string& name) {
  if (name == "LN_BOBYQA") return nlopt::LN_BOBYQA;
  if (name == "LN_SBPLX") return nlopt::LN_SBPLX;
  if (name == "LN_NELDERMEAD") return nlopt::LN_NELDERMEAD;
  if (name == "LN_COBYLA") return nlopt::LN_COBYLA;
  throw std::invalid_argument("local_algorithm '" + name + "' is not one of LN_BOBYQA, LN_SBPLX, LN_NELDERMEAD, LN_COBYLA");
}

void validateSetup(const TuneSetup& s) {
  if (s.params.empty()) throw std::invalid_argument("no gains to tune: params is empty");
  for (std::size_t i = 0; i < s.params.size(); ++i) {
    if (!isGainName(s.params[i]))
      throw std::invalid_argument("unknown parameter '" + s.params[i] + "' in params (known: " + joinedGainNames() + ")");
    if (std::find(s.params.begin(), s.params.begin() + static_cast<long>(i), s.params[i]) !=
        s.params.begin() + static_cast<long>(i))
      throw std::invalid_argument("parameter '" + s.params[i] + "' is listed twice in params");
  }
  for (const auto& [name, b] : s.bounds) {
    if (!isGainName(name))
      throw std::invalid_argument("bounds given for unknown parameter '" + name + "' (known: " + joinedGainNames() + ")");
    if (!std::isfinite(b.first) || !std::isfinite(b.second) || !(b.first < b.second))
      throw std::invalid_argument("bounds of " + name + " [" + significant(b.first, 6) + ", " + significant(b.second, 6) +
                                  "] must be finite with lo < hi");
    double lo = 0, hi = 0;
    control::gainBounds(name, lo, hi);
    if (b.first < lo || b.second > hi)
      throw std::invalid_argument("bounds of " + name + " [" + significant(b.first, 6) + ", " + significant(b.second, 6) +
                                  "] are outside the allowed range [" + significant(lo, 6) + ", " + significant(hi, 6) + "]");
  }
  if (const auto e = control::validatePlant(s.plant); !e.empty()) throw std::invalid_argument("plant: " + e);
  if (s.plant_variations < 1)
    throw std::invalid_argument("plant_variations = " + std::to_string(s.plant_variations) + " must be >= 1");
  if (s.seeds < 1) throw std::invalid_argument("seeds = " + std::to_string(s.seeds) + " must be >= 1");
  if (s.max_evals < 10) throw std::invalid_argument("max_evals = " + std::to_string(s.max_evals) + " must be >= 10");
  if (s.threads < 0) throw std::invalid_argument("threads = " + std::to_string(s.threads) + " must be >= 0");
  if (!(s.gain_spread >= 0 && s.gain_spread < 1))
    throw std::invalid_argument("gain_spread = " + significant(s.gain_spread, 6) + " must be in [0, 1)");
  if (!(s.tau_spread >= 0 && s.tau_spread < 1))
    throw std::invalid_argument("tau_spread = " + significant(s.tau_spread, 6) + " must be in [0, 1)");
  if (!(s.dead_spread_s >= 0 && s.dead_spread_s <= 1))
    throw std::invalid_argument("dead_spread_s = " + significant(s.dead_spread_s, 6) + " must be in [0, 1]");
  if (!(s.global_fraction >= 0 && s.global_fraction <= 1))
    throw std::invalid_argument("global_fraction = " + significant(s.global_fraction, 6) + " must be in [0, 1]");
  const CostWeights& w = s.weights;
  for (const auto& [name, v] : {std::pair{"max_pos", w.max_pos}, std::pair{"rms_pos", w.rms_pos},
                                std::pair{"max_ang", w.max_ang}, std::pair{"rms_ang", w.rms_ang},
                                std::pair{"convergence", w.convergence}, std::pair{"effort", w.effort},
                                std::pair{"saturation", w.saturation}})
    if (!(std::isfinite(v) && v >= 0))
      throw std::invalid_argument(std::string("weight ") + name + " = " + significant(v, 6) + " must be finite and >= 0");
  globalAlgorithm(s.global_algorithm);
  localAlgorithm(s.local_algorithm);
}

/// Variation 0 is the plant; the others spread gain (+-gain_spread), time
/// constant (+-tau_spread) and dead time (+0 .. +dead_spread_s: a model
/// rarely overestimates delay) of each wheel on a Latin hypercube whose
/// levels include the extremes, permuted by `seed` (mt19937: the same
/// scenarios on every platform).
std::vector<control::PlantModel> plantVariations(const TuneSetup& s) {
  std::vector<control::PlantModel> out{s.plant};
  const int n = s.plant_variations - 1;
  if (n <= 0) return out;
  constexpr int kDims = 6;  // per wheel: gain, time constant, dead time
  std::mt19937 rng(s.seed);
  std::vector<std::vector<double>> u(kDims, std::vector<double>(static_cast<std::size_t>(n)));
  for (auto& dim : u) {
    for (int k = 0; k < n; ++k)
      dim[static_cast<std::size_t>(k)] = n == 1 ? ((rng() & 1u) ? 1.0 : -1.0) : -1.0 + 2.0 * k / (n - 1);
    for (int i = n - 1; i > 0; --i) std::swap(dim[static_cast<std::size_t>(i)], dim[rng() % static_cast<uint32_t>(i + 1)]);
  }
  auto perturb = [&](const control::WheelMotorModel& m, double ug, double ut, double ud) {
    control::WheelMotorModel p = m;
    p.gain = std::clamp(m.gain * (1.0 + s.gain_spread * ug), 0.2, 5.0);
    p.time_constant_s = std::clamp(m.time_constant_s * (1.0 + s.tau_spread * ut), 0.001, 5.0);
    p.dead_time_s = std::clamp(m.dead_time_s + s.dead_spread_s * (ud + 1.0) / 2.0, 0.0, 1.0);
    return p;
  };
  for (std::size_t k = 0; k < static_cast<std::size_t>(n); ++k) {
    control::PlantModel p;
    p.left = perturb(s.plant.left, u[0][k], u[1][k], u[2][k]);
    p.right = perturb(s.plant.right, u[3][k], u[4][k], u[5][k]);
    out.push_back(p);
  }
  return out;
}

/// Effort of an ideal run: the reference's own wheel speeds (Eq 13 of the
/// path's v and w, clamped to the wheel limit) over the path, tick by tick.
double referenceEffort(const control::ReferencePath& path, const control::TrackerParams& t, double dt_s) {
  control::PathProgress progress;
  double effort = 0;
  constexpr long kMaxTicks = 10000000;  // 28 h at 100 Hz: a guard, not a limit any real path meets
  for (long k = 0; k < kMaxTicks && !progress.done; ++k) {
    const control::ReferenceState ref = control::advance(path, progress, 1.0, dt_s);
    if (progress.done) break;
    const auto w = control::wheelsFromTwist({ref.v_m_s, ref.w_rad_s}, t.wheel_radius_m, t.track_m);
    const double l = std::clamp(w.left_rad_s, -t.max_wheel_speed_rad_s, t.max_wheel_speed_rad_s);
    const double r = std::clamp(w.right_rad_s, -t.max_wheel_speed_rad_s, t.max_wheel_speed_rad_s);
    effort += (l * l + r * r) * dt_s;
  }
  return effort;
}

}  // namespace

// ---------------------------------------------------------------- cost

double costOf(const sim::ClosedLoopMetrics& m, const CostWeights& w, double reference_effort) {
  for (MetricField f : kMetricFields)
    if (!std::isfinite(m.*f)) return kNonFiniteCost;
  if (m.max_pos_err_m > kDivergedPosition_m) return kDivergedCost + std::min(m.max_pos_err_m, 1000.0);
  double c = w.max_pos * m.max_pos_err_m / kPosScale_m + w.rms_pos * m.rms_pos_err_m / kRmsPosScale_m +
             w.max_ang * m.max_ang_err_rad / kAngScale_rad + w.rms_ang * m.rms_ang_err_rad / kRmsAngScale_rad +
             w.convergence * (m.converge_pos_s + m.converge_ang_s) / 2.0 / kConvergenceScale_s;
  if (reference_effort > 0 && std::isfinite(reference_effort))
    c += w.effort * std::max(0.0, m.effort / reference_effort - 1.0);
  if (m.duration_s > 0) c += w.saturation * kSaturationScale * m.saturated_s / m.duration_s;
  // convergenceTime() returns the run's end when the error is outside the band at the end.
  const double end = m.duration_s - 0.005;
  if (m.duration_s > 0 && m.converge_pos_s >= end) c += kNotConvergedPenalty;
  if (m.duration_s > 0 && m.converge_ang_s >= end) c += kNotConvergedPenalty;
  return std::min(c, kDivergedCost);
}

// ---------------------------------------------------------------- tuner

struct Tuner::Impl {
  TuneSetup setup;
  std::vector<double> lo, hi;  // per parameter
  std::vector<control::PlantModel> plants;
  double reference_effort = 0;
  sim::ClosedLoopConfig base;
  std::unique_ptr<WorkerPool> pool;
  struct Search;

  sim::ClosedLoopConfig configFor(const control::GainSet& g, control::WheelControl wc) const {
    sim::ClosedLoopConfig cfg = base;
    cfg.tracker.aux = g.aux;
    cfg.tracker.fuzzy = g.fuzzy;  // .base holds the PID gains for kPid (as TrajectoryTracker uses them)
    cfg.tracker.wheel_control = wc;
    return cfg;
  }

  Evaluation evaluate(const control::GainSet& g, control::WheelControl wc) const {
    const int seeds = setup.seeds;
    const int count = static_cast<int>(plants.size()) * seeds;
    const sim::ClosedLoopConfig proto = configFor(g, wc);
    std::vector<sim::ClosedLoopMetrics> runs(static_cast<std::size_t>(count));
    pool->run(count, [&](int i, const SchedulerPtr& sched) {
      sim::ClosedLoopConfig cfg = proto;
      cfg.plant = plants[static_cast<std::size_t>(i / seeds)];
      cfg.seed = setup.seed + static_cast<uint32_t>(i % seeds);
      runs[static_cast<std::size_t>(i)] =
          sim::runClosedLoop(cfg, setup.reference.makePath(), wc == control::WheelControl::kFuzzyPid ? sched : nullptr,
                             false)
              .metrics;
    });
    Evaluation ev;
    ev.scenarios = count;
    ev.nominal = runs.front();
    ev.worst = runs.front();
    double sum = 0, worst = -std::numeric_limits<double>::infinity();
    for (const auto& r : runs) {
      const double c = costOf(r, setup.weights, reference_effort);
      sum += c;
      worst = std::max(worst, c);
      for (MetricField f : kMetricFields) {
        ev.mean.*f += r.*f / count;
        ev.worst.*f = std::max(ev.worst.*f, r.*f);
      }
    }
    ev.cost = sum / count + worst;
    return ev;
  }

  control::GainSet gainsAt(const control::GainSet& start, const double* x) const {
    control::GainSet g = start;
    for (std::size_t i = 0; i < setup.params.size(); ++i)
      *control::gainByName(g, setup.params[i]) = lo[i] + std::clamp(x[i], 0.0, 1.0) * (hi[i] - lo[i]);
    return g;
  }
};

Tuner::Tuner(TuneSetup setup) : impl_(std::make_unique<Impl>()) {
  validateSetup(setup);
  Impl& im = *impl_;
  config::applyRobot(setup.control, setup.robot);
  for (const auto& name : setup.params) {
    const auto it = setup.bounds.find(name);
    const auto b = it != setup.bounds.end() ? it->second : defaultTuneBounds(name);
    im.lo.push_back(b.first);
    im.hi.push_back(b.second);
  }
  const auto path = setup.reference.makePath();  // throws std::invalid_argument for a bad reference
  im.base.robot = setup.robot;
  im.base.tracker = setup.control.tracker;
  im.plants = plantVariations(setup);
  for (const auto& p : im.plants)
    if (const auto e = control::validatePlant(p); !e.empty())
      throw std::invalid_argument("plant variation: " + e);  // unreachable: variations are clamped to the valid ranges
  im.reference_effort = referenceEffort(*path, im.base.tracker, im.base.control_dt_s);
  const int threads =
      setup.threads > 0 ? setup.threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  try {
    im.pool = std::make_unique<WorkerPool>(threads, setup.fis, setup.control.use_lookup);
  } catch (const fuzzy::FisError& e) {
    throw std::invalid_argument(std::string("fis: ") + e.what());
  }
  im.setup = std::move(setup);
}

Tuner::~Tuner() = default;

const TuneSetup& Tuner::setup() const { return impl_->setup; }

Evaluation Tuner::evaluate(const control::GainSet& g, control::WheelControl wc) const {
  return impl_->evaluate(g, wc);
}

sim::ClosedLoopResult Tuner::trace(const control::GainSet& g, control::WheelControl wc, uint32_t seed) const {
  sim::ClosedLoopConfig cfg = impl_->configFor(g, wc);
  cfg.plant = impl_->setup.plant;
  cfg.seed = seed;
  sim::ClosedLoopResult out;
  impl_->pool->run(1, [&](int, const SchedulerPtr& sched) {
    out = sim::runClosedLoop(cfg, impl_->setup.reference.makePath(),
                             wc == control::WheelControl::kFuzzyPid ? sched : nullptr, true);
  });
  return out;
}

/// State of one run(): the budget, the best so far, what NLopt's callbacks need.
struct Tuner::Impl::Search {
  const Tuner::Impl* impl = nullptr;
  control::GainSet start;
  const std::function<void(const TuneProgress&)>* progress = nullptr;
  const std::atomic<bool>* cancel = nullptr;
  Clock::time_point t0;
  TuneResult* result = nullptr;
  std::vector<double> best_x;
  std::map<std::vector<double>, double> seen;  // evaluated points (NLopt revisits its start points)
  nlopt::opt* opt = nullptr;
  std::string phase;
  bool cancelled = false;
  std::exception_ptr error;

  bool cancelRequested() const { return cancel && cancel->load(); }

  void record(const control::GainSet& g, const Evaluation& e) {
    TuneResult& r = *result;
    ++r.evals;
    if (e.cost < r.best_eval.cost) {
      r.best = g;
      r.best_eval = e;
    }
    r.best_cost_history.push_back(r.best_eval.cost);
    if (progress && *progress) {
      TuneProgress p;
      p.evals = r.evals;
      p.max_evals = impl->setup.max_evals;
      p.best_cost = r.best_eval.cost;
      p.initial_cost = r.initial_eval.cost;
      p.best = r.best;
      p.elapsed_s = std::chrono::duration<double>(Clock::now() - t0).count();
      p.phase = phase;
      (*progress)(p);
    }
  }

  double objective(const double* x) {
    const std::size_t n = impl->setup.params.size();
    std::vector<double> key(x, x + n);
    if (const auto it = seen.find(key); it != seen.end()) return it->second;
    if (cancelRequested()) {
      cancelled = true;
      opt->force_stop();
      return result->best_eval.cost;
    }
    if (result->evals >= impl->setup.max_evals) {
      opt->force_stop();
      return result->best_eval.cost;
    }
    try {
      const control::GainSet g = impl->gainsAt(start, x);
      const Evaluation e = impl->evaluate(g, control::WheelControl::kFuzzyPid);
      const bool better = e.cost < result->best_eval.cost;
      record(g, e);
      if (better) best_x = key;
      seen.emplace(std::move(key), e.cost);
      return e.cost;
    } catch (...) {
      error = std::current_exception();
      opt->force_stop();
      return result->best_eval.cost;
    }
  }

  static double callback(unsigned, const double* x, double*, void* data) {
    return static_cast<Search*>(data)->objective(x);
  }

  /// One NLopt phase over [0, 1]^n from best_x with `budget` evaluations;
  /// NLopt's own stops (forced, roundoff) keep the best so far.
  void runPhase(nlopt::algorithm alg, int budget, const std::string& name, double initial_step) {
    if (cancelRequested()) cancelled = true;
    if (budget <= 0 || cancelled || error) return;
    const unsigned n = static_cast<unsigned>(impl->setup.params.size());
    nlopt::opt o(alg, n);
    o.set_lower_bounds(std::vector<double>(n, 0.0));
    o.set_upper_bounds(std::vector<double>(n, 1.0));
    o.set_min_objective(&Search::callback, this);
    // The start point comes from the cache, so it does not use up the budget.
    o.set_maxeval(budget + 1);
    if (initial_step > 0) {
      o.set_initial_step(initial_step);
      o.set_xtol_abs(1e-4);
    }
    opt = &o;
    phase = name;
    std::vector<double> x = best_x;
    double f = 0;
    try {
      o.optimize(x, f);
    } catch (const nlopt::forced_stop&) {
    } catch (const nlopt::roundoff_limited&) {
    } catch (const std::invalid_argument&) {
      opt = nullptr;
      throw;
    } catch (const std::runtime_error&) {  // NLOPT_FAILURE: keep the best so far
    }
    opt = nullptr;
  }
};

TuneResult Tuner::run(const control::GainSet& start, const std::function<void(const TuneProgress&)>& progress,
                      const std::atomic<bool>* cancel) {
  if (const auto e = control::validateGains(start); !e.empty())
    throw std::invalid_argument("start gains: " + e);
  const Impl& im = *impl_;
  const TuneSetup& s = im.setup;
  const std::size_t n = s.params.size();
  const nlopt::algorithm global = globalAlgorithm(s.global_algorithm);
  nlopt::algorithm local = localAlgorithm(s.local_algorithm);
  std::string local_name = s.local_algorithm;

  TuneResult r;
  Impl::Search search;
  search.impl = &im;
  search.start = start;
  search.progress = &progress;
  search.cancel = cancel;
  search.t0 = Clock::now();
  search.result = &r;
  search.phase = "global";
  r.initial = start;
  r.best = start;

  // The start is the first evaluation and the incumbent: the result is never worse.
  r.initial_eval = im.evaluate(start, control::WheelControl::kFuzzyPid);
  r.best_eval = r.initial_eval;
  r.best_eval.cost = std::numeric_limits<double>::infinity();
  search.record(start, r.initial_eval);
  search.best_x.resize(n);
  bool start_inside = true;
  for (std::size_t i = 0; i < n; ++i) {
    const double v = gainValue(start, s.params[i]);
    const double u = (v - im.lo[i]) / (im.hi[i] - im.lo[i]);
    start_inside = start_inside && u >= 0.0 && u <= 1.0;
    search.best_x[i] = std::clamp(u, 0.0, 1.0);
  }
  // A start outside the search box is moved onto it (a new point); inside, NLopt's first call is the start.
  if (start_inside) search.seen.emplace(search.best_x, r.initial_eval.cost);

  nlopt::srand(s.seed);
  const int global_budget = std::min(s.max_evals, static_cast<int>(std::lround(s.global_fraction * s.max_evals))) - r.evals;
  search.runPhase(global, global_budget, "global", 0.0);
  const int left = s.max_evals - r.evals;
  // BOBYQA needs two dimensions and 2n + 1 points to build its first model.
  if (local == nlopt::LN_BOBYQA && (n < 2 || left < static_cast<int>(2 * n + 3))) {
    local = nlopt::LN_SBPLX;
    local_name = "LN_SBPLX";
  }
  // A local run stops when its steps fall below the tolerance; restarts from
  // the best point with steps of 0.1, 0.03, 0.01 (cycling) use the rest of the
  // budget. A round that only revisits known points ends the polish.
  constexpr double kSteps[] = {0.1, 0.03, 0.01};
  for (int round = 0; r.evals < s.max_evals && !search.cancelled && !search.error; ++round) {
    const int before = r.evals;
    search.runPhase(local, s.max_evals - r.evals, "local", kSteps[round % 3]);
    if (r.evals == before) break;
  }
  if (search.error) std::rethrow_exception(search.error);
  r.cancelled = search.cancelled;
  r.wall_s = std::chrono::duration<double>(Clock::now() - search.t0).count();
  r.algorithm = s.global_algorithm + " + " + local_name;
  return r;
}

}  // namespace inspect::tuning
