// social_arena's figures for people and programs: per policy over all
// episodes (summarize), the tables, the pattern confusion, false people with
// and without the site map, the worst episodes, the Pareto and episode
// plots, a CSV row per episode and policy, and the JSON (docs/scenarios.md,
// "The arena").
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numeric>

#include "experiments/arena/social_arena_parts.hpp"
#include "shared/util/gnuplot.hpp"

namespace inspect::arena_cli {

using arena::Policy;

std::string patternName(int k) {
  return k == arena::kUnseen ? "unseen" : std::string(behavior::toString(static_cast<behavior::Pattern>(k)));
}

Summary summarize(const std::vector<EpisodeResult>& rs, std::size_t k) {
  Summary s;
  for (const auto& r : rs) {
    const auto& m = r.by_policy[k];
    ++s.episodes;
    s.success += m.success ? 1 : 0;
    s.timeouts += m.timeout ? 1 : 0;
    s.robot_fault += m.robot_fault;
    s.person_fault += m.person_fault;
    s.robot_fault_episodes += m.robot_fault > 0 ? 1 : 0;
    s.person_fault_episodes += m.person_fault > 0 ? 1 : 0;
    s.intimate_s += m.intimate_s;
    s.intimate_episodes += m.intimate_s > 0 ? 1 : 0;
    s.intimate_robot_s += m.intimate_robot_s;
    s.intimate_robot_episodes += m.intimate_robot_s > 0 ? 1 : 0;
    s.personal_s += m.personal_s;
    s.irregularity += m.irregularity_rad_m;
    s.jerk += m.max_jerk_m_s3;
    if (m.min_gap_m >= 0) {
      s.min_gap = std::min(s.min_gap, m.min_gap_m);
      s.min_gap_sum += m.min_gap_m;
      ++s.gap_n;
    }
    if (m.time_lost_s > -1e8 && m.time_to_goal_s >= 0 && r.reference.time_to_goal_s >= 0) {
      ++s.completed;
      s.time_lost_s += m.time_lost_s;
      s.lost.push_back(m.time_lost_s);
    }
    for (int a = 0; a < arena::kPatterns; ++a)
      for (int b = 0; b <= arena::kPatterns; ++b) s.confusion[a][b] += m.confusion[a][b];
    if (m.true_dominant > 0) {
      ++s.dominant_n;
      s.dominant_right += m.reported_dominant == m.true_dominant ? 1 : 0;
    }
    s.false_people += m.false_people;
    s.minutes += m.duration_s / 60.0;
  }
  std::sort(s.lost.begin(), s.lost.end());
  return s;
}

double ratio(uint64_t a, uint64_t b) { return b ? static_cast<double>(a) / static_cast<double>(b) : 0.0; }

Accuracy accuracy(const arena::Confusion& c) {
  Accuracy a;
  for (int t = 0; t < arena::kPatterns; ++t)
    for (int r = 0; r <= arena::kPatterns; ++r) {
      a.ticks += c[t][r];
      if (r != arena::kUnseen) a.seen += c[t][r];
      if (r == t) {
        a.right += c[t][r];
        a.seen_right += c[t][r];
      }
    }
  return a;
}

namespace {

double percentile(const std::vector<double>& v, double q) {
  if (v.empty()) return 0;
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5))];
}

void printConfusion(const arena::Confusion& c, const char* title) {
  std::printf("\n%s (rows: true pattern, columns: reported; ticks)\n", title);
  std::printf("%-13s", "true \\ rep");
  for (int r = 0; r <= arena::kPatterns; ++r) std::printf(" %12s", patternName(r).c_str());
  std::printf(" %8s\n", "right");
  for (int t = 0; t < arena::kPatterns; ++t) {
    uint64_t row = 0;
    for (int r = 0; r <= arena::kPatterns; ++r) row += c[t][r];
    std::printf("%-13s", patternName(t).c_str());
    for (int r = 0; r <= arena::kPatterns; ++r) std::printf(" %12llu", static_cast<unsigned long long>(c[t][r]));
    std::printf(" %7.1f%%\n", 100.0 * ratio(c[t][t], row));
  }
}

nlohmann::ordered_json confusionJson(const arena::Confusion& c) {
  nlohmann::ordered_json j;
  for (int t = 0; t < arena::kPatterns; ++t) {
    nlohmann::ordered_json row;
    for (int r = 0; r <= arena::kPatterns; ++r) row[patternName(r)] = c[t][r];
    j[patternName(t)] = row;
  }
  return j;
}

// How bad an episode went for a policy (for "worst"): robot-at-fault
// contacts first, then intimate time the robot caused, then any, a timeout, the smallest gap.
double badness(const arena::EpisodeMetrics& m) {
  return 1e6 * m.robot_fault + 100.0 * m.intimate_robot_s + m.intimate_s + (m.timeout ? 50.0 : 0.0) +
         (m.min_gap_m >= 0 ? 2.0 - std::min(2.0, m.min_gap_m) : 0.0);
}

std::string plotPareto(const std::string& path, const std::array<Summary, kP>& sums) {
  plot::Panel p = plot::panel("arena: time lost vs personal-zone time (mean per episode, one point per policy)",
                              "time lost (s)", "personal-zone time (s)");
  const char* colors[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e"};
  for (std::size_t k = 0; k < kP; ++k) {
    plot::Series s = plot::series(arena::toString(arena::kPolicies[k]), colors[k]);
    s.style = "points pt 7 ps 2";
    s.x = {sums[k].meanLost()};
    s.y = {sums[k].meanPersonal()};
    p.series.push_back(s);
    p.labels.push_back({sums[k].meanLost(), sums[k].meanPersonal(), std::string("  ") + arena::toString(arena::kPolicies[k]),
                        colors[k]});
  }
  p.key = "outside right";
  return plot::renderPng(path, {p}, 900, 500);
}

/// False people where nobody is (the references, with and without the site
/// map) and, with people, the strategy's, by where they were.
struct FalsePeople {
  uint32_t false_map = 0, false_nomap = 0;
  double min_map = 0, min_nomap = 0;
  arena::FalseWhere where_nomap{}, where_people{};
  // Active looking: looks started and the PTZ head's time off the path, in the
  // strategy's runs and in the no-map references.
  uint32_t looks = 0, looks_nomap = 0;
  double off_path_s = 0, off_path_nomap_s = 0, min_strategy = 0;
};

FalsePeople falsePeople(const std::vector<EpisodeResult>& results) {
  FalsePeople fp;
  for (const auto& r : results) {
    fp.false_map += r.reference.false_people;
    fp.min_map += r.reference.duration_s / 60.0;
    fp.false_nomap += r.reference_no_map.false_people;
    fp.min_nomap += r.reference_no_map.duration_s / 60.0;
    fp.looks += r.by_policy[0].looks;
    fp.off_path_s += r.by_policy[0].ptz_off_path_s;
    fp.min_strategy += r.by_policy[0].duration_s / 60.0;
    fp.looks_nomap += r.reference_no_map.looks;
    fp.off_path_nomap_s += r.reference_no_map.ptz_off_path_s;
    for (int k = 0; k < arena::kFalseWhereKinds; ++k) {
      fp.where_nomap[static_cast<std::size_t>(k)] += r.reference_no_map.false_where[static_cast<std::size_t>(k)];
      fp.where_people[static_cast<std::size_t>(k)] += r.by_policy[0].false_where[static_cast<std::size_t>(k)];
    }
  }
  return fp;
}

void printMix(const Options& o, const std::vector<EpisodeResult>& results, double wall_s) {
  // --- episode mix ---
  int aisles = 0, people = 0;
  std::array<int, 4> behaviours{};
  for (const auto& r : results) {
    aisles += r.episode.layout == arena::Layout::kAisle ? 1 : 0;
    people += static_cast<int>(r.episode.people.size());
    for (const auto& p : r.episode.people) ++behaviours[static_cast<std::size_t>(p.behaviour)];
  }
  std::printf("social_arena: seed %llu, %zu episodes (%d aisle, %zu crossing), %d people (regular %d, not reacting %d, "
              "stop-and-go %d, together %d), %zu runs in %.1f s on %d threads\n",
              static_cast<unsigned long long>(o.seed), results.size(), aisles, results.size() - aisles, people,
              behaviours[0], behaviours[1], behaviours[2], behaviours[3], results.size() * (kP + 2), wall_s, o.threads);

}

void printPolicies(const std::array<Summary, kP>& sums) {
  std::printf("\n%-15s %7s %6s %11s %12s %8s %9s %9s %9s %9s %9s %9s %8s %8s\n", "policy", "success", "tmout",
              "robot-fault", "person-fault", "min gap", "mean gap", "intim s", "intim ep", "robot ep", "pers s",
              "lost s", "irreg", "jerk");
  for (std::size_t k = 0; k < kP; ++k) {
    const auto& s = sums[k];
    std::printf("%-15s %6.1f%% %6d %5u (%3u ep) %6u (%3u ep) %8.2f %9.2f %9.2f %9d %9d %9.2f %9.2f %8.3f %8.2f\n",
                arena::toString(arena::kPolicies[k]), 100.0 * ratio(static_cast<uint64_t>(s.success), static_cast<uint64_t>(s.episodes)),
                s.timeouts, s.robot_fault, s.robot_fault_episodes, s.person_fault, s.person_fault_episodes,
                s.gap_n ? s.min_gap : 0.0, s.gap_n ? s.min_gap_sum / s.gap_n : 0.0,
                s.episodes ? s.intimate_s / s.episodes : 0.0, s.intimate_episodes, s.intimate_robot_episodes,
                s.meanPersonal(), s.meanLost(),
                s.episodes ? s.irregularity / s.episodes : 0.0, s.episodes ? s.jerk / s.episodes : 0.0);
  }
  std::printf("(per episode means; intim: someone's body within 0.45 m of the robot's, ep: episodes with any, robot ep:\n"
              " with the robot moving towards them while there; min gap body to body over all episodes; lost: mean over completed episodes, "
              "against the same episode without people; irreg rad/m; jerk: max per episode, m/s^3)\n");

}

void printPatterns(const std::array<Summary, kP>& sums) {
  const Accuracy acc = accuracy(sums[0].confusion);
  printConfusion(sums[0].confusion, "strategy: reported vs true pattern on observable ticks");
  std::printf("pattern accuracy: %.1f%% of %llu observable ticks (%.1f%% of the %llu the robot tracked someone); "
              "dominant pattern right in %d of %d episodes (%.1f%%)\n",
              100.0 * ratio(acc.right, acc.ticks), static_cast<unsigned long long>(acc.ticks),
              100.0 * ratio(acc.seen_right, acc.seen), static_cast<unsigned long long>(acc.seen), sums[0].dominant_right,
              sums[0].dominant_n, 100.0 * ratio(static_cast<uint64_t>(sums[0].dominant_right), static_cast<uint64_t>(sums[0].dominant_n)));

}

void printFalsePeople(const FalsePeople& fp, const std::array<Summary, kP>& sums) {
  std::printf("\nfalse people (nobody in the world, driving the aisles): with the site map %u in %.1f min "
              "(%.3f/min), without %u in %.1f min (%.3f/min); with people, strategy: %u in %.1f min\n",
              fp.false_map, fp.min_map, fp.min_map > 0 ? fp.false_map / fp.min_map : 0.0, fp.false_nomap, fp.min_nomap,
              fp.min_nomap > 0 ? fp.false_nomap / fp.min_nomap : 0.0, sums[0].false_people, sums[0].minutes);
  std::printf("false people by where they were (the camera's view: +-hfov/2 of the heading; reached: its detector's "
              "recall > 0 there)\n  %-18s %10s %18s\n", "where", "no map", "with people (strategy)");
  for (int k = 0; k < arena::kFalseWhereKinds; ++k)
    std::printf("  %-18s %10u %18u\n", arena::falseWhereName(k), fp.where_nomap[static_cast<std::size_t>(k)],
                fp.where_people[static_cast<std::size_t>(k)]);

}

void printVsBaselines(const std::array<Summary, kP>& sums) {
  const auto& st = sums[0];
  const auto& sw = sums[2];
  const auto& orc = sums[4];
  std::printf("\nstrategy vs stop_and_wait: time lost %.2f vs %.2f s, personal-zone %.2f vs %.2f s; vs oracle: "
              "time lost %+.0f%%, personal-zone %+.0f%%\n",
              st.meanLost(), sw.meanLost(), st.meanPersonal(), sw.meanPersonal(),
              orc.meanLost() > 0 ? 100.0 * (st.meanLost() / orc.meanLost() - 1) : 0.0,
              orc.meanPersonal() > 0 ? 100.0 * (st.meanPersonal() / orc.meanPersonal() - 1) : 0.0);

}

/// The episodes, the strategy's worst first (badness).
std::vector<std::size_t> worstFirst(const std::vector<EpisodeResult>& results) {
  // Worst episodes of the strategy.
  std::vector<std::size_t> order(results.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return badness(results[a].by_policy[0]) > badness(results[b].by_policy[0]); });
  return order;
}

void printWorst(const Options& o, const std::vector<EpisodeResult>& results, const std::vector<std::size_t>& order,
                std::size_t worst_n) {
  std::printf("\nworst episodes of the strategy (replay: social_arena --seed %llu --episode K; world: --print-world):\n",
              static_cast<unsigned long long>(o.seed));
  for (std::size_t w = 0; w < std::min<std::size_t>(std::max<std::size_t>(worst_n, 5), order.size()); ++w) {
    const auto& r = results[order[w]];
    const auto& m = r.by_policy[0];
    std::string who;
    for (const auto& p : r.episode.people)
      who += (who.empty() ? "" : ", ") + std::string(arena::toString(p.behaviour)) + " " +
             std::to_string(static_cast<int>(std::lround(p.heading_deg))) + " deg";
    std::printf("  K=%-4d %-8s w %.1f m: robot-fault %u, person-fault %u, intimate %.2f s, min gap %.2f m, %s [%s]\n",
                r.episode.index, arena::toString(r.episode.layout), r.episode.width_m, m.robot_fault, m.person_fault,
                m.intimate_s, m.min_gap_m, m.success ? "ok" : m.failure.c_str(), who.c_str());
  }

}

void writePlots(const Options& o, const std::vector<EpisodeResult>& results, const std::array<Summary, kP>& sums,
                const std::vector<std::size_t>& order, std::size_t worst_n,
                const std::vector<sim::ScenarioContext>& contexts) {
  std::error_code ec;
  std::filesystem::create_directories(o.plots, ec);
  std::string err = plotPareto(o.plots + "/pareto.png", sums);
  for (std::size_t w = 0; w < worst_n && err.empty(); ++w) {
    const auto& r = results[order[w]];
    std::vector<sim::ScenarioRun> runs;
    for (Policy p : {Policy::kStrategy, Policy::kPlain, Policy::kStopAndWait}) {
      sim::ScenarioRun run;
      (void)arena::runEpisode(r.episode, contexts[0], p, r.reference.time_to_goal_s, o.camera, true, &run);
      runs.push_back(std::move(run));
    }
    err = sim::plotScenario(o.plots, r.episode.spec, runs);
  }
  if (!err.empty()) std::fprintf(stderr, "social_arena: plots: %s\n", err.c_str());
  else std::printf("plots in %s (pareto.png, arena_<K>.png)\n", o.plots.c_str());
}

void writeCsv(const Options& o, const std::vector<EpisodeResult>& results) {
  std::ofstream f(o.csv);
  f << "episode,seed,layout,width_m,cross_angle_deg,people,behaviours,policy,success,timeout,robot_fault,"
       "person_fault,min_gap_m,intimate_s,intimate_robot_s,personal_s,time_to_goal_s,time_lost_s,irregularity_rad_m,max_jerk_m_s3,"
       "observable_ticks,right_ticks,true_dominant,reported_dominant,false_people\n";
  for (const auto& r : results) {
    std::string beh;
    for (const auto& p : r.episode.people) beh += (beh.empty() ? "" : ";") + std::string(arena::toString(p.behaviour));
    for (std::size_t k = 0; k < kP; ++k) {
      const auto& m = r.by_policy[k];
      const Accuracy a = accuracy(m.confusion);
      char line[640];
      std::snprintf(line, sizeof line, "%d,%llu,%s,%.1f,%.1f,%zu,%s,%s,%d,%d,%u,%u,%.3f,%.2f,%.2f,%.2f,%.2f,%.2f,%.4f,%.2f,%llu,%llu,%s,%s,%u\n",
                    r.episode.index, static_cast<unsigned long long>(r.episode.seed), arena::toString(r.episode.layout),
                    r.episode.width_m, r.episode.cross_angle_deg, r.episode.people.size(), beh.c_str(),
                    arena::toString(arena::kPolicies[k]), m.success ? 1 : 0, m.timeout ? 1 : 0, m.robot_fault,
                    m.person_fault, m.min_gap_m, m.intimate_s, m.intimate_robot_s, m.personal_s, m.time_to_goal_s, m.time_lost_s,
                    m.irregularity_rad_m, m.max_jerk_m_s3, static_cast<unsigned long long>(a.ticks),
                    static_cast<unsigned long long>(a.right), m.true_dominant > 0 ? patternName(m.true_dominant).c_str() : "",
                    m.reported_dominant > 0 ? patternName(m.reported_dominant).c_str() : "", m.false_people);
      f << line;
    }
  }
  if (!f) std::fprintf(stderr, "social_arena: cannot write %s\n", o.csv.c_str());
}

void writeJson(const Options& o, const std::vector<EpisodeResult>& results, const std::array<Summary, kP>& sums,
               const FalsePeople& fp, double wall_s) {
  nlohmann::ordered_json j;
  j["seed"] = o.seed;
  j["episodes"] = results.size();
  j["wall_s"] = wall_s;
  j["threads"] = o.threads;
  for (std::size_t k = 0; k < kP; ++k) {
    const auto& s = sums[k];
    nlohmann::ordered_json p;
    p["success"] = s.success;
    p["timeouts"] = s.timeouts;
    p["robot_fault_collisions"] = s.robot_fault;
    p["robot_fault_episodes"] = s.robot_fault_episodes;
    p["person_fault_collisions"] = s.person_fault;
    p["person_fault_episodes"] = s.person_fault_episodes;
    p["min_gap_m"] = s.gap_n ? s.min_gap : 0.0;
    p["mean_min_gap_m"] = s.gap_n ? s.min_gap_sum / s.gap_n : 0.0;
    p["intimate_s_mean"] = s.episodes ? s.intimate_s / s.episodes : 0.0;
    p["intimate_episodes"] = s.intimate_episodes;
    p["intimate_robot_s_mean"] = s.episodes ? s.intimate_robot_s / s.episodes : 0.0;
    p["intimate_robot_episodes"] = s.intimate_robot_episodes;
    p["personal_s_mean"] = s.meanPersonal();
    p["time_lost_s_mean"] = s.meanLost();
    p["time_lost_s_p90"] = percentile(s.lost, 0.9);
    p["irregularity_rad_m_mean"] = s.episodes ? s.irregularity / s.episodes : 0.0;
    p["max_jerk_m_s3_mean"] = s.episodes ? s.jerk / s.episodes : 0.0;
    const Accuracy a = accuracy(s.confusion);
    p["pattern_accuracy"] = ratio(a.right, a.ticks);
    p["pattern_accuracy_tracked"] = ratio(a.seen_right, a.seen);
    p["dominant_right"] = s.dominant_right;
    p["dominant_episodes"] = s.dominant_n;
    p["false_people"] = s.false_people;
    p["minutes"] = s.minutes;
    p["confusion"] = confusionJson(s.confusion);
    j["policies"][arena::toString(arena::kPolicies[k])] = p;
  }
  j["false_people"] = {{"with_map", fp.false_map},       {"with_map_min", fp.min_map},
                       {"without_map", fp.false_nomap}, {"without_map_min", fp.min_nomap}};
  if (fp.looks + fp.looks_nomap > 0)
    j["active_look"] = {{"looks", fp.looks},
                        {"off_path_s", fp.off_path_s},
                        {"minutes", fp.min_strategy},
                        {"looks_no_map", fp.looks_nomap},
                        {"off_path_no_map_s", fp.off_path_nomap_s},
                        {"minutes_no_map", fp.min_nomap}};
  for (int k = 0; k < arena::kFalseWhereKinds; ++k) {
    j["false_people"]["without_map_where"][arena::falseWhereName(k)] = fp.where_nomap[static_cast<std::size_t>(k)];
    j["false_people"]["strategy_where"][arena::falseWhereName(k)] = fp.where_people[static_cast<std::size_t>(k)];
  }
  std::ofstream f(o.json);
  f << j.dump(2) << "\n";
  if (!f) std::fprintf(stderr, "social_arena: cannot write %s\n", o.json.c_str());
}

}  // namespace

void report(const Options& o, const std::vector<EpisodeResult>& results,
            const std::vector<sim::ScenarioContext>& contexts, double wall_s) {
  printMix(o, results, wall_s);
  std::array<Summary, kP> sums;
  for (std::size_t k = 0; k < kP; ++k) sums[k] = summarize(results, k);
  printPolicies(sums);
  printPatterns(sums);
  const FalsePeople fp = falsePeople(results);
  printFalsePeople(fp, sums);
  if (fp.looks + fp.looks_nomap > 0)
    std::printf("active look: strategy %u looks, the PTZ head off the path %.1f s of %.1f min (%.1f %%); no-map "
                "references %u looks, off the path %.1f %%\n",
                fp.looks, fp.off_path_s, fp.min_strategy,
                fp.min_strategy > 0 ? 100.0 * fp.off_path_s / (60.0 * fp.min_strategy) : 0.0, fp.looks_nomap,
                fp.min_nomap > 0 ? 100.0 * fp.off_path_nomap_s / (60.0 * fp.min_nomap) : 0.0);
  printVsBaselines(sums);
  const std::vector<std::size_t> order = worstFirst(results);
  const std::size_t worst_n = std::min<std::size_t>(static_cast<std::size_t>(std::max(o.worst, 0)), order.size());
  printWorst(o, results, order, worst_n);
  if (!o.plots.empty()) writePlots(o, results, sums, order, worst_n, contexts);
  if (!o.csv.empty()) writeCsv(o, results);
  if (!o.json.empty()) writeJson(o, results, sums, fp, wall_s);
}

}  // namespace inspect::arena_cli
