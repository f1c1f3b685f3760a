// The console's tuning commands (docs/tuning.md): identify <run>, tune, gains.
// The tuning host's state (plant, working gains, last session) lives in one
// TuningState per console; it is created on first use from the robot and
// control configs (config/robot.yaml, config/control.yaml by default).
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "pc_server/console/console.hpp"
#include "pc_server/console/run_commands.hpp"
#include "pc_server/console/text_util.hpp"
#include "pc_server/console/tuning_commands.hpp"
#include "pc_server/console/tuning_state.hpp"
#include "pc_server/recording/recorder.hpp"
#include "pc_server/tuning/plant_id.hpp"
#include "pc_server/tuning/tuner.hpp"
#include "pc_server/tuning/tuning_report.hpp"
#include "shared/config/config_node.hpp"
#include "shared/config/control_config.hpp"
#include "shared/config/gains_file.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/fuzzy/fis_reader.hpp"
#include "shared/fuzzy/fis_writer.hpp"
#include "shared/net/gains_proto.hpp"
#include "shared/util/clock.hpp"
#include "sim/robot_plant.hpp"

namespace inspect::server {

using namespace args;
using Source = ArgSpec::Source;

namespace fs = std::filesystem;

namespace {

std::string wheelLine(const char* name, const control::WheelMotorModel& m) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "%-5s gain %.3f  time constant %.3f s  dead time %.3f s  saturation %.2f rad/s", name,
                m.gain, m.time_constant_s, m.dead_time_s, m.saturation_rad_s);
  return buf;
}

constexpr double kMaxTuneReference_s = 300.0;
constexpr double kTuneMinSpeed_m_s = 0.05;

std::string sessionStamp() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t t = std::chrono::system_clock::to_time_t(now);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%d-%H%M%S", &tm);
  return buf;
}

}  // namespace

void TuningCommands::setPaths(std::string robot_config, std::string control_config, std::string dir) {
  tune_.robot_config = std::move(robot_config);
  tune_.control_config = std::move(control_config);
  tune_.dir = std::move(dir);
  tune_.state.reset();
}

TuningState* TuningCommands::tuning(const std::string& cmd) {
  if (tune_.state) return tune_.state.get();
  try {
    auto t = std::make_shared<TuningState>();
    auto loaded = config::loadTrackingSetup(tune_.robot_config, tune_.control_config);
    t->robot = std::move(loaded.robot);
    t->control = std::move(loaded.control);
    t->fis = std::move(loaded.fis);
    t->paper.fuzzy = t->control.tracker.fuzzy;
    t->paper.aux = t->control.tracker.aux;
    t->working = t->paper;
    t->plant = sim::nominalPlant(t->robot);
    tune_.state = std::move(t);
  } catch (const std::exception& e) {
    c_.fail(cmd, std::string("cannot load the tuning configs: ") + e.what());
    return nullptr;
  }
  return tune_.state.get();
}

// ------------------------------------------------------------------ identify

bool TuningCommands::cmdIdentify(const CommandArgs& a) {
  TuningState* ts = tuning("identify");
  if (!ts) return false;
  if (!c_.recorder()) return c_.fail("identify", "the server records nothing (--no-record): there are no runs");
  std::string id = a.text("run-id|last");
  if (id == "last") {
    // The newest run that played a wheel test (an identification route).
    catalog::RunFilter f;
    f.limit = 50;
    for (const auto& r : c_.recorder()->catalog().listRuns(f))
      if (r.name.rfind("identification", 0) == 0) {
        id = r.id;
        break;
      }
    if (id == "last") return c_.fail("identify", "no identification run in the catalog (route identification records one)");
  }
  const auto run = findRun(c_, "identify", id);
  if (!run) return false;
  const auto& [d, dir] = *run;
  tuning::PlantFit fit;
  tuning::RunWheelData data;
  try {
    data = tuning::readRunWheelSeries(dir + "/run.mcap");
    tuning::IdentifyOptions o;
    o.nominal_saturation_rad_s = ts->robot.limits.max_wheel_speed_rad_s;
    fit = tuning::identifyPlant(data.left, data.right, o);
  } catch (const std::exception& e) {
    return c_.fail("identify", "run " + d.info.id + ": " + e.what());
  }
  c_.out() << "identify: run " << d.info.id << " (" << d.info.name << "): " << data.samples_used << " of "
       << data.telemetry_messages << " telemetry samples, " << fmtShort(fit.duration_s, 1) << " s, grid "
       << fmtShort(fit.sample_period_s * 1000.0, 3) << " ms\n";
  for (const auto& [name, w] : {std::pair{"left", &fit.left}, std::pair{"right", &fit.right}}) {
    c_.out() << "  " << wheelLine(name, w->model) << "  fit " << fmtFixed(w->fit_percent, 1) << " %  rms "
         << fmtShort(w->rms_error_rad_s, 3) << " rad/s" << (w->saturation_observed ? "" : "  (saturation not reached: nominal)")
         << "\n";
  }
  const auto nominal = sim::nominalPlant(ts->robot);
  c_.out() << "  nominal (config/robot.yaml): gain 1, time constant " << fmtShort(nominal.left.time_constant_s, 3)
       << " s, no dead time\n";
  for (const auto& w : fit.warnings) c_.out() << "  warning: " << w << "\n";
  const std::string path = dir + "/plant.yaml";
  try {
    std::ofstream f(path);
    f << tuning::plantYaml(fit, "run " + d.info.id);
    if (!f) throw std::runtime_error("cannot write " + path);
    f.close();
    std::error_code ec;
    c_.recorder()->catalog().addFile(d.info.id, "plant", path, static_cast<int64_t>(fs::file_size(path, ec)));
  } catch (const std::exception& e) {
    return c_.fail("identify", e.what());
  }
  ts->plant = fit.model;
  ts->plant_source = "identified from run " + d.info.id;
  c_.out() << "identify: model saved as " << path << "; tune now uses it\n";
  return true;
}

// ---------------------------------------------------------------------- tune

bool TuningCommands::cmdTuneList() {
  // The tuning sessions in the catalog, newest first.
  // The tuning sessions in the catalog, newest first.
  if (!c_.recorder()) return c_.fail("tune", "the server records nothing (--no-record): no catalog of sessions");
  const auto list = c_.recorder()->catalog().listTuningSessions(20);
  if (list.empty()) {
    c_.out() << "no tuning sessions in the catalog\n";
    return true;
  }
  for (const auto& t : list) {
    char line[512];
    std::snprintf(line, sizeof line, "%-34s %-8s %-36s %5lld evals %7.1f s  cost %.4g -> %.4g%s  %s\n", t.id.c_str(),
                  t.robot.empty() ? "-" : t.robot.c_str(), t.reference.c_str(), static_cast<long long>(t.evals),
                  t.wall_s, t.initial_cost, t.best_cost, t.cancelled ? " (cancelled)" : "", t.dir.c_str());
    c_.out() << line;
  }
  return true;
}

std::vector<ArgSpec> TuningCommands::tuneOptionKeys() {
  using namespace args;
  const auto count = [](const char* key, double lo, double hi) { return within(integer(key), lo, hi); };
  return {choice("ref", {"circle", "line", "waypoints"}),
          within(number("radius"), 0.5, 50.0),
          within(number("speed"), kTuneMinSpeed_m_s, 10.0),  // and at most the robot's max_v (applyTuneOptions)
          within(number("laps"), 0.1, 10.0),
          within(number("length"), 1.0, 100.0),
          count("evals", 10, 100000),
          count("variations", 1, 64),
          count("seeds", 1, 64),
          count("threads", 0, 64),
          count("seed", 0, 4294967295.0),
          word("params"),
          word("plant"),
          choice("start", {"working", "paper", "tuned"})};
}

std::string TuningCommands::applyTuneOptions(const CommandArgs& a, TuningState& ts, tuning::TuneSetup& s,
                                      std::string& plant_source, std::string& start) {
  // Types and ranges are checked by the command table (tuneOptionKeys); what
  // depends on this robot and these files is checked here.
  const auto number = [&a](const char* key) { return a.number(std::string("options.") + key); };
  const auto text = [&a](const char* key) -> const std::string& { return a.text(std::string("options.") + key); };
  if (const std::string& ref = text("ref"); !ref.empty()) {
    using K = tuning::TuneReference::Kind;
    s.reference.kind = ref == "circle" ? K::kCircle : ref == "line" ? K::kLine : K::kWaypoints;
  }
  if (const auto x = number("radius")) s.reference.radius_m = *x;
  if (const auto x = number("speed")) {
    if (*x > ts.robot.limits.max_v_m_s)
      return "speed=" + text("speed") + ": expected a number in [" + fmtShort(kTuneMinSpeed_m_s) + ", " +
             fmtShort(ts.robot.limits.max_v_m_s) + "] (the robot's max_v)";
    s.reference.speed_m_s = *x;
  }
  if (const auto x = number("laps")) s.reference.laps = *x;
  if (const auto x = number("length")) s.reference.length_m = *x;
  if (const auto x = number("evals")) s.max_evals = static_cast<int>(*x);
  if (const auto x = number("variations")) s.plant_variations = static_cast<int>(*x);
  if (const auto x = number("seeds")) s.seeds = static_cast<int>(*x);
  if (const auto x = number("threads")) s.threads = static_cast<int>(*x);
  if (const auto x = number("seed")) s.seed = static_cast<uint32_t>(*x);
  if (const std::string& v = text("params"); !v.empty()) {
    s.params.clear();
    if (v == "all") {
      s.params.assign(control::kGainNames.begin(), control::kGainNames.end());
    } else {
      std::stringstream ss(v);
      std::string p;
      while (std::getline(ss, p, ',')) {
        control::GainSet probe;
        if (!control::gainByName(probe, p))
          return "params: unknown gain '" + p + "' (kp ki kd ke kec k1 k2 k3 a1 a2 a3, or all)";
        s.params.push_back(p);
      }
    }
  }
  if (const std::string& v = text("plant"); !v.empty() && v != "current") {
    if (v == "nominal") {
      s.plant = sim::nominalPlant(ts.robot);
      plant_source = "nominal (config/robot.yaml)";
    } else {
      try {
        std::string path = v;
        if (!fs::exists(path) && c_.recorder()) {  // a run id: its identified plant
          path = c_.recorder()->config().dir + "/" + v + "/plant.yaml";
          if (!fs::exists(path))
            return "plant=" + v + ": no such file, and no run '" + v + "' with plant.yaml (identify it first)";
        }
        s.plant = tuning::loadPlantFile(path);
        plant_source = "from " + path;
      } catch (const std::exception& e) {
        return std::string("plant=") + v + ": " + e.what();
      }
    }
  }
  if (const std::string& v = text("start"); !v.empty()) {
    if (v == "tuned" && !ts.tuned) return "start=tuned: nothing tuned yet";
    start = v;
  }
  return "";
}

std::optional<tuning::TuneResult> TuningCommands::runTuner(tuning::Tuner& tuner, const control::GainSet& start_gains) {
  std::atomic<bool>& cancel = tune_.cancel;  // outlives the command: the signal handler may still hold it
  cancel.store(false);
  c_.stopFlag().setInterruptTarget(&cancel);
  const bool tty = c_.alarmStyle();  // an interactive terminal: one redrawn progress line
  int last_decile = -1;
  const double t0 = c_.nowS();
  double last_draw_s = -1.0;
  tuning::TuneResult result;
  try {
    result = tuner.run(
        start_gains,
        [&](const tuning::TuneProgress& p) {
          if (c_.stopFlag().requested()) cancel.store(true);
          const double el = c_.nowS() - t0;
          const double frac = p.max_evals > 0 ? static_cast<double>(p.evals) / p.max_evals : 1.0;
          const int decile = static_cast<int>(frac * 10.0);
          char line[200];
          std::string bar(20, '.');
          for (int i = 0; i < static_cast<int>(frac * 20.0) && i < 20; ++i) bar[static_cast<std::size_t>(i)] = '#';
          std::snprintf(line, sizeof line, "[%s] %4d/%d evals  best cost %.4g (start %.4g, %+.1f %%)  %s  %.1f s",
                        bar.c_str(), p.evals, p.max_evals, p.best_cost, p.initial_cost,
                        p.initial_cost > 0 ? 100.0 * (p.best_cost - p.initial_cost) / p.initial_cost : 0.0,
                        p.phase.c_str(), el);
          if (tty) {
            if (el - last_draw_s >= 0.1 || p.evals == p.max_evals) {
              c_.out() << "\r\x1b[K" << line << std::flush;
              last_draw_s = el;
            }
          } else if (decile != last_decile) {
            c_.out() << "  " << line << "\n" << std::flush;
            last_decile = decile;
          }
        },
        &cancel);
  } catch (const std::exception& e) {
    c_.stopFlag().setInterruptTarget(nullptr);
    if (tty) c_.out() << "\n";
    c_.fail("tune", e.what());
    return std::nullopt;
  }
  c_.stopFlag().setInterruptTarget(nullptr);
  if (tty) c_.out() << "\n";
  return result;
}

std::optional<std::string> TuningCommands::saveTuneSession(const tuning::TuneSetup& setup, const tuning::TuneResult& result,
                                                    const tuning::Comparison& cmp, const std::string& params,
                                                    const std::string& robot) {
  TuningState* ts = tune_.state.get();
  std::string session = sessionStamp() + "-tune" + (robot.empty() ? "" : "-" + robot);
  for (int n = 2; fs::exists(tune_.dir + "/" + session) && n < 1000; ++n)  // two sessions in one second
    session = sessionStamp() + "-tune" + (robot.empty() ? "" : "-" + robot) + "-" + std::to_string(n);
  const std::string dir = tune_.dir + "/" + session;
  try {
    const auto files = tuning::writeTuningSession(dir, setup, result, cmp, ts->fis);
    for (const auto& n : files.notes) c_.out() << "  note: " << n << "\n";
    c_.out() << "tune: session " << session << ": " << files.files.size() << " files in " << dir << "/\n";
  } catch (const std::exception& e) {
    c_.fail("tune", "cannot write the session: " + std::string(e.what()));
    return std::nullopt;
  }
  if (c_.recorder()) {
    catalog::TuningSession cs;
    cs.id = session;
    cs.created = std::chrono::system_clock::now();
    cs.robot = robot;
    cs.reference = setup.reference.describe();
    cs.plant_json = tuning::plantJson(setup.plant);
    cs.params = params;
    cs.algorithm = result.algorithm;
    cs.evals = result.evals;
    cs.wall_s = result.wall_s;
    cs.cancelled = result.cancelled;
    cs.initial_cost = result.initial_eval.cost;
    cs.best_cost = result.best_eval.cost;
    cs.initial_gains_json = config::gainsJson(result.initial);
    cs.best_gains_json = config::gainsJson(result.best);
    cs.dir = dir;
    try {
      c_.recorder()->catalog().addTuningSession(cs);
    } catch (const std::exception& e) {
      c_.out() << "tune: warning: session not in the catalog: " << e.what() << "\n";
    }
  }
  return session;
}

bool TuningCommands::cmdTune(const CommandArgs& a) {
  if (a.has("list")) return cmdTuneList();
  TuningState* ts = tuning("tune");
  if (!ts) return false;
  tuning::TuneSetup s;
  s.robot = ts->robot;
  s.control = ts->control;
  s.fis = ts->fis;
  s.plant = ts->plant;
  std::string plant_source = ts->plant_source;
  std::string start = "working";
  if (const std::string why = applyTuneOptions(a, *ts, s, plant_source, start); !why.empty())
    return c_.fail("tune", why);
  const control::GainSet start_gains = start == "paper" ? ts->paper : start == "tuned" ? *ts->tuned : ts->working;
  // Each run's samples are held in memory: a reference longer than 5 minutes
  // (a slow, many-lap circle) would cost gigabytes and minutes per evaluation.
  try {
    const auto path = s.reference.makePath();
    double t = 0.0;
    for (double d = 0.0; d < path->length_m(); d += 0.05) t += 0.05 / std::max(1e-3, path->at(d).speed_m_s);
    if (t > kMaxTuneReference_s)
      return c_.fail("tune", s.reference.describe() + " lasts " + fmtShort(t, 0) + " s: at most " +
                              fmtShort(kMaxTuneReference_s, 0) + " s (fewer laps, a smaller radius or a higher speed)");
  } catch (const std::exception& e) {
    return c_.fail("tune", e.what());
  }
  std::unique_ptr<tuning::Tuner> tuner;
  try {
    tuner = std::make_unique<tuning::Tuner>(s);
  } catch (const std::exception& e) {
    return c_.fail("tune", e.what());
  }
  const auto& setup = tuner->setup();
  std::string params;
  for (const auto& p : setup.params) params += (params.empty() ? "" : ",") + p;
  c_.out() << "tune: " << setup.reference.describe() << "; plant " << plant_source << "\n"
       << "  " << wheelLine("left", setup.plant.left) << "\n  " << wheelLine("right", setup.plant.right) << "\n"
       << "  tuning " << params << " from the " << start << " gains; " << setup.max_evals << " evaluations x "
       << setup.plant_variations * setup.seeds << " runs (" << setup.plant_variations << " plant variations x "
       << setup.seeds << " noise seeds); Ctrl-C stops and keeps the best so far\n";
  c_.out().flush();

  const auto result = runTuner(*tuner, start_gains);
  if (!result) return false;
  c_.out() << "tune: " << (result->cancelled ? "cancelled after " : "done: ") << result->evals << " evaluations in "
       << fmtShort(result->wall_s, 3) << " s (" << result->algorithm << "); cost " << fmtShort(result->initial_eval.cost, 4)
       << " -> " << fmtShort(result->best_eval.cost, 4) << "\n";
  c_.out() << "  best: " << gainsText(result->best) << "\n";

  // PID and fuzzy-PID with the paper's gains against the tuned set.
  tuning::Comparison cmp;
  try {
    cmp = tuning::compareControllers(*tuner, {{"PID (paper)", control::WheelControl::kPid, ts->paper},
                                              {"fuzzy-PID (paper)", control::WheelControl::kFuzzyPid, ts->paper},
                                              {"fuzzy-PID (tuned)", control::WheelControl::kFuzzyPid, result->best}});
  } catch (const std::exception& e) {
    return c_.fail("tune", std::string("comparison: ") + e.what());
  }
  c_.out() << tuning::comparisonTable(cmp);
  const std::string robot = c_.selected();
  const auto session = saveTuneSession(setup, *result, cmp, params, robot);
  if (!session) return false;
  ts->tuned = result->best;
  ts->tuned_session = *session;
  ts->working = result->best;
  ts->last_session_dir = tune_.dir + "/" + *session;
  c_.out() << "tune: the working gains are now the tuned set; `gains push` sends them to " << (robot.empty() ? "the selected robot" : robot)
       << "\n";
  return true;
}

// --------------------------------------------------------------------- gains

bool TuningCommands::pushGains(const std::string& robot, const control::GainSet& g, const std::string& source,
                        const std::string& session) {
  TuningState* ts = tuning("gains");
  if (!ts) return false;
  if (const std::string why = control::validateGains(g); !why.empty()) return c_.fail("gains", "not pushed: " + why);
  v1::Command c;
  auto* u = c.mutable_gains();
  net::toProto(g, *u->mutable_gains());
  u->set_source(source);
  if (ts->fis_imported) u->set_fis(fuzzy::formatFis(ts->fis));
  const CallResult r = c_.outcomeOf(c_.service().send(c_.session(), robot, "gains push", std::move(c), c_.clock().nowNs()));
  if (r.outcome == CallOutcome::kInvalid || r.outcome == CallOutcome::kRefused) return c_.report(r);  // nothing sent
  if (r.outcome == CallOutcome::kTimedOut) {
    c_.countError();
    c_.out() << r.text() << "\n";
    return false;
  }
  const v1::Ack& ack = r.ack;
  const bool ok = ack.status() == v1::Ack::ACCEPTED;
  if (ok) {
    c_.out() << robot << ": gains v" << ack.gains_version() << " accepted (" << ack.reason() << ")\n";
  } else {
    c_.countError();
    c_.out() << robot << ": gains push rejected: " << ack.reason() << " (v" << ack.gains_version() << " stays in force)\n";
  }
  if (c_.recorder()) {
    catalog::GainsPush p;
    p.robot = robot;
    p.time = std::chrono::system_clock::now();
    p.version = ack.gains_version();
    p.gains_json = config::gainsJson(g);
    p.status = ok ? "accepted" : "rejected";
    p.reason = ok ? "" : ack.reason();
    p.session_id = session;
    try {
      c_.recorder()->catalog().addGainsPush(p);
    } catch (const std::exception& e) {
      c_.out() << "gains: warning: push not in the catalog: " << e.what() << "\n";
    }
  }
  return ok;
}

// Commands of the tuning host (docs/tuning.md).
std::vector<ConsoleCommand> TuningCommands::commands() {
  return {
    {"identify", {{word("run-id|last")}}, "fit the hub-motor model to a recorded run (for tune)",
     "  Fits each wheel's gain, time constant, dead time and saturation to the commanded and\n"
     "  measured wheel speeds of the run's telemetry (an output-error fit), prints the model and\n"
     "  its fit (100 % = perfect), saves <run>/plant.yaml and makes it the plant tune uses.\n"
     "  'last' = the newest identification run. Record one with `route identification`.\n"
     "  example: identify last\n",
     handler(this, &TuningCommands::cmdIdentify)},
    {"tune", {{subcommand("list")}, {opt(keyValues("options", "key=value ...", tuneOptionKeys()))}}, "optimise the fuzzy-PID gains in simulation (NLopt), compare, save a session",
     "  Closed-loop simulations of the robot's own tracker on the plant (nominal, or the last\n"
     "  `identify`), each candidate over plant variations x noise seeds; cost = weighted max/RMS\n"
     "  position and angle error, convergence time, effort and saturation (docs/tuning.md).\n"
     "  Options: ref=circle|line|waypoints radius=3.5 speed=0.5 laps=1 length=10\n"
     "           params=kp,ki,kd,ke,kec,k1,k2,k3 (or all, adds a1,a2,a3) evals=1000\n"
     "           plant=current|nominal|<run-id>|<plant.yaml> variations=4 seeds=2 threads=0 seed=1\n"
     "           start=working|paper|tuned\n"
     "  Shows a progress bar and the best cost; Ctrl-C stops and keeps the best so far. Then\n"
     "  prints PID vs fuzzy-PID (paper gains) vs tuned, writes plots and summary.md into\n"
     "  runs/tuning/<session>/, books the session in the catalog and makes the tuned set the\n"
     "  working set (gains push sends it). `tune list`: the sessions in the catalog.\n"
     "  example: tune evals=300 speed=0.5\n",
     handler(this, &TuningCommands::cmdTune)},
    {"gains",
     {{subcommand("show"), opt(completing(word("robot"), Source::kRobots))},
      {keyword("set"), choice("preset", {"paper", "tuned", "robot"})},
      {keyword("set"), keyValues("gains", "<name>=<value>...")},
      {keyword("push"), opt(completing(word("robot"), Source::kRobots))},
      {keyword("revert"), opt(completing(word("robot"), Source::kRobots))},
      {keyword("export"), word("file.yaml")},
      {keyword("import"), word("file.yaml")}},
     "the tracking gains: working set, push to a robot, revert, files",
     "  show: working set, the robot's set in force (with its version), the paper's, the tuned.\n"
     "  set: edit the working set (kp ki kd ke kec k1 k2 k3 a1 a2 a3; bounds are checked).\n"
     "  push: send the working set; the robot checks it, applies it at its next control tick\n"
     "    (also to a path being tracked) and answers with the version now in force, or why not.\n"
     "  revert: push the set the robot had in force before its current one.\n"
     "  export/import: a YAML file of the gains plus the .fis fuzzy system beside it; an\n"
     "    imported .fis that differs from the loaded one is pushed with the gains.\n"
     "  example: gains set kp=12 ki=3\n  example: gains push\n",
     handler(this, &TuningCommands::cmdGains)},
  };
}

}  // namespace inspect::server
