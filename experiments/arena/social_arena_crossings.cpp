// social_arena --crossings (docs/scenarios.md, "Crossing at angles"): the
// eight crossing cases of issue 61 (45 and 135 degrees, fast and slow, a
// walker who yields and one who does not; arena::crossingCases), each with
// the strategy, the oracle and a reference run without people: on the ticks
// the crossing person is observable and truly crossing, how often the robot
// reports "crossing", and what it reports instead.
#include <atomic>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <thread>

#include "experiments/arena/social_arena_parts.hpp"

namespace inspect::arena_cli {

namespace {

constexpr int kCrossing = static_cast<int>(behavior::Pattern::kCrossing);

struct CaseRun {
  arena::CrossingCase c;
  arena::EpisodeMetrics strategy, oracle, reference;
};

/// The crossing row of a confusion matrix: observable ticks truly crossing, by what was reported.
uint64_t crossingTicks(const arena::EpisodeMetrics& m) {
  uint64_t n = 0;
  for (int r = 0; r <= arena::kPatterns; ++r) n += m.confusion[kCrossing][r];
  return n;
}

double pct(uint64_t a, uint64_t b) { return 100.0 * ratio(a, b); }

}  // namespace

int crossings(const Options& o, const std::vector<sim::ScenarioContext>& contexts) {
  const auto cases = arena::crossingCases();
  std::vector<CaseRun> runs(cases.size());
  std::atomic<std::size_t> next{0};
  std::mutex err_mu;
  std::string error;
  auto worker = [&](int tid) {
    const auto& ctx = contexts[static_cast<std::size_t>(tid)];
    for (std::size_t i = next++; i < cases.size(); i = next++) {
      try {
        const arena::Episode e = arena::crossingEpisode(cases[i]);
        CaseRun& r = runs[i];
        r.c = cases[i];
        r.reference = arena::runReference(e, ctx, o.camera, true);
        r.strategy = arena::runEpisode(e, ctx, arena::Policy::kStrategy, r.reference.time_to_goal_s, o.camera);
        r.oracle = arena::runEpisode(e, ctx, arena::Policy::kOracle, r.reference.time_to_goal_s, o.camera);
      } catch (const std::exception& ex) {
        std::lock_guard lk(err_mu);
        if (error.empty()) error = cases[i].name() + ": " + ex.what();
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < o.threads; ++t) pool.emplace_back(worker, t);
  for (auto& t : pool) t.join();
  if (!error.empty()) {
    std::fprintf(stderr, "social_arena: %s\n", error.c_str());
    return 2;
  }

  std::printf("\nCrossing at angles (issue 61; camera %s, heads %s): the ticks the crossing person is observable\n"
              "and truly crossing, and what the strategy reported on them (%%). Target: crossing on >= 80 %%.\n\n",
              !o.camera.enabled ? "none" : o.camera.real ? "real" : "model", o.camera.wide_head ? "both" : "ptz");
  std::printf("| case | ticks | crossing | leading | confronting | encountering | none | unseen | dominant | "
              "personal s (oracle) | lost s (oracle) | robot-fault (oracle) |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  nlohmann::json cj = nlohmann::json::array();
  uint64_t all_ticks = 0, all_right = 0;
  for (const auto& r : runs) {
    const auto& m = r.strategy;
    const uint64_t n = crossingTicks(m);
    const auto& row = m.confusion[kCrossing];
    all_ticks += n;
    all_right += row[kCrossing];
    const auto at = [&](behavior::Pattern p) { return pct(row[static_cast<int>(p)], n); };
    std::printf("| %s | %llu | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %s | %.2f (%.2f) | %.2f (%.2f) | %u (%u) |\n",
                r.c.name().c_str(), static_cast<unsigned long long>(n), at(behavior::Pattern::kCrossing),
                at(behavior::Pattern::kLeading), at(behavior::Pattern::kConfronting),
                at(behavior::Pattern::kEncountering), at(behavior::Pattern::kNone), pct(row[arena::kUnseen], n),
                m.reported_dominant < 0 ? "-" : patternName(m.reported_dominant).c_str(), m.personal_s,
                r.oracle.personal_s, m.time_lost_s, r.oracle.time_lost_s, m.robot_fault, r.oracle.robot_fault);
    nlohmann::json j;
    j["case"] = r.c.name();
    j["angle_deg"] = r.c.angle_deg;
    j["speed_m_s"] = r.c.speed_m_s;
    j["yields"] = r.c.yields;
    j["crossing_ticks"] = n;
    nlohmann::json by = nlohmann::json::object();
    for (int k = 0; k <= arena::kPatterns; ++k) by[patternName(k)] = row[k];
    j["reported"] = by;
    j["crossing_pct"] = pct(row[kCrossing], n);
    j["dominant"] = m.reported_dominant < 0 ? "" : patternName(m.reported_dominant);
    j["personal_s"] = m.personal_s;
    j["oracle_personal_s"] = r.oracle.personal_s;
    j["time_lost_s"] = m.time_lost_s;
    j["oracle_time_lost_s"] = r.oracle.time_lost_s;
    j["robot_fault"] = m.robot_fault;
    j["person_fault"] = m.person_fault;
    j["oracle_robot_fault"] = r.oracle.robot_fault;
    j["success"] = m.success;
    cj.push_back(j);
  }
  std::printf("\nAll eight: crossing reported on %.1f %% of %llu observable crossing ticks.\n", pct(all_right, all_ticks),
              static_cast<unsigned long long>(all_ticks));
  if (!o.json.empty()) {
    nlohmann::json j;
    j["cases"] = cj;
    j["crossing_ticks"] = all_ticks;
    j["crossing_pct"] = pct(all_right, all_ticks);
    j["camera"] = !o.camera.enabled ? "none" : o.camera.real ? "real" : "model";
    j["heads"] = o.camera.wide_head ? "both" : "ptz";
    std::ofstream f(o.json);
    f << j.dump(2) << "\n";
    if (!f) {
      std::fprintf(stderr, "social_arena: cannot write %s\n", o.json.c_str());
      return 2;
    }
  }
  return 0;
}

}  // namespace inspect::arena_cli
