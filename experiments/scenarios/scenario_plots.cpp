// PNG figures of a scenario like the paper's Figures 13-16 and 19: the paths of
// the robot and the people with time marks, the robot's speed over time, and
// the distance to the nearest person over time with Hall's zones shaded.
#include <cmath>
#include <limits>

#include "shared/util/gnuplot.hpp"
#include "experiments/scenarios/scenario.hpp"

namespace inspect::sim {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const char* const kPolicyColor[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd"};  // fuzzy, none, stop_and_wait, fuzzy_no_pattern
const char* const kPeopleColor[] = {"#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#bcbd22"};

const char* policyColor(behavior::SpeedPolicy p) { return kPolicyColor[static_cast<int>(p)]; }

std::string policyTitle(behavior::SpeedPolicy p) {
  switch (p) {
    case behavior::SpeedPolicy::kFuzzy: return "robot, fuzzy strategy (Eq 9)";
    case behavior::SpeedPolicy::kNone: return "robot, plain tracking";
    case behavior::SpeedPolicy::kStopAndWait: return "robot, stop-and-wait";
    case behavior::SpeedPolicy::kFuzzyNoPattern: return "robot, Eq 9 without the pattern";
  }
  return "robot";
}

// Walls and obstacle edges as one series with gaps.
plot::Series wallSeries(const World& w) {
  plot::Series s{"walls", {}, {}, "lines", "#555555", 2, false};
  auto seg = [&](double x0, double y0, double x1, double y1) {
    s.x.insert(s.x.end(), {x0, x1, kNaN});
    s.y.insert(s.y.end(), {y0, y1, kNaN});
  };
  for (const auto& e : w.walls) seg(e.a.x, e.a.y, e.b.x, e.b.y);
  for (const auto& o : w.obstacles) {
    const auto& v = o.polygon.vertices;
    for (std::size_t i = 0; i < v.size(); ++i) seg(v[i].x, v[i].y, v[(i + 1) % v.size()].x, v[(i + 1) % v.size()].y);
  }
  return s;
}

}  // namespace

std::string plotScenario(const std::string& dir, const ScenarioSpec& spec, const std::vector<ScenarioRun>& runs) {
  if (runs.empty()) return "no runs to plot";
  plot::Panel paths{spec.name + ": paths (marks every 2 s)", "x (m)", "y (m)", {}, {}, {}, true, "outside right", ""};
  paths.series.push_back(wallSeries(spec.world));
  constexpr double kMark_s = 2.0;
  for (const auto& r : runs) {
    if (!r.people) continue;
    plot::Series s{policyTitle(r.policy), {}, {}, "lines", policyColor(r.policy), 2,
                   r.policy != behavior::SpeedPolicy::kFuzzy};
    plot::Series marks{"", {}, {}, "points pt 7 ps 0.6", policyColor(r.policy), 1, false};
    double next = 0;
    for (const auto& q : r.series) {
      s.x.push_back(q.x_m);
      s.y.push_back(q.y_m);
      if (q.t_s + 1e-9 >= next) {
        marks.x.push_back(q.x_m);
        marks.y.push_back(q.y_m);
        if (r.policy == behavior::SpeedPolicy::kFuzzy)
          paths.labels.push_back({q.x_m, q.y_m, std::to_string(static_cast<int>(std::lround(q.t_s))), policyColor(r.policy)});
        next += kMark_s;
      }
    }
    paths.series.push_back(std::move(s));
    paths.series.push_back(std::move(marks));
  }
  // People as seen in the first (fuzzy) run.
  const ScenarioRun& first = runs.front();
  for (std::size_t i = 0; i < first.people_paths.size(); ++i) {
    const auto& pp = first.people_paths[i];
    const char* col = kPeopleColor[i % (sizeof kPeopleColor / sizeof *kPeopleColor)];
    plot::Series s{"person " + pp.id, pp.x_m, pp.y_m, "lines", col, 2, false};
    plot::Series marks{"", {}, {}, "points pt 5 ps 0.6", col, 1, false};
    double next = pp.t_s.empty() ? 0 : std::ceil(pp.t_s.front() / kMark_s) * kMark_s;
    for (std::size_t k = 0; k < pp.t_s.size(); ++k)
      if (pp.t_s[k] + 1e-9 >= next) {
        marks.x.push_back(pp.x_m[k]);
        marks.y.push_back(pp.y_m[k]);
        paths.labels.push_back({pp.x_m[k], pp.y_m[k], std::to_string(static_cast<int>(std::lround(pp.t_s[k]))), col});
        next += kMark_s;
      }
    paths.series.push_back(std::move(s));
    paths.series.push_back(std::move(marks));
  }

  plot::Panel speed{"robot speed", "t (s)", "v (m/s)", {}, {}, {}, false, "top right", ""};
  plot::Panel dist{"distance to the nearest person (centres); zones: intimate < 0.45 m, personal < 1.2 m",
                   "t (s)", "distance (m)", {}, {}, {}, false, "top right", ""};
  dist.yrange = "[0:*]";  // the zones start at 0
  dist.bands.push_back({0.0, 0.45, "#f4b6b6", "intimate"});
  dist.bands.push_back({0.45, 1.2, "#fbe3b5", "personal"});
  for (const auto& r : runs) {
    if (!r.people) continue;
    plot::Series v{policyTitle(r.policy), {}, {}, "lines", policyColor(r.policy), 2,
                   r.policy != behavior::SpeedPolicy::kFuzzy};
    plot::Series d = v;
    plot::Series est{"robot's estimate (fuzzy)", {}, {}, "points pt 7 ps 0.3", "#7f7f7f", 1, false};
    for (const auto& q : r.series) {
      v.x.push_back(q.t_s);
      v.y.push_back(q.v_m_s);
      d.x.push_back(q.t_s);
      d.y.push_back(q.person_m >= 0 ? q.person_m : kNaN);
      if (r.policy == behavior::SpeedPolicy::kFuzzy && q.detected_m >= 0) {
        est.x.push_back(q.t_s);
        est.y.push_back(q.detected_m);
      }
    }
    speed.series.push_back(std::move(v));
    dist.series.push_back(std::move(d));
    if (!est.x.empty()) dist.series.push_back(std::move(est));
  }
  return plot::renderPng(dir + "/" + spec.name + ".png", {paths, speed, dist}, 1000, 420);
}

}  // namespace inspect::sim
