#include "experiments/arena/episode.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "shared/world/world.hpp"

namespace inspect::arena {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kRobotSpeed_m_s = 0.5;   // the paper's experiments
constexpr double kRobotStartup_s = 1.0;   // command at 20 ms, then the speed ramps up
constexpr double kFarY_m = 6.0;           // the cross aisle's ends
constexpr double kWallClear_m = 0.32;     // a route point keeps this from a wall (radius 0.25 + margin)
constexpr double kTogetherGap_m = 0.7;    // centre to centre, side by side
constexpr double kTimeLimit_s = 60.0;

// splitmix64 (Steele, Lea & Flood 2014): tiny, portable, good enough to draw
// a few dozen numbers per episode.
class Draw {
 public:
  explicit Draw(uint64_t seed) : s_(seed) {}
  uint64_t next() {
    uint64_t z = (s_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  double uniform(double lo, double hi) {
    return lo + (hi - lo) * static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0);
  }
  int pick(int n) { return static_cast<int>(next() % static_cast<uint64_t>(n)); }
  bool chance(double p) { return uniform(0, 1) < p; }
  template <class T, std::size_t N>
  T among(const T (&v)[N]) {
    return v[pick(static_cast<int>(N))];
  }

 private:
  uint64_t s_;
};

struct Pt {
  double x, y;
};
Pt operator+(Pt a, Pt b) { return {a.x + b.x, a.y + b.y}; }
Pt operator-(Pt a, Pt b) { return {a.x - b.x, a.y - b.y}; }
Pt operator*(double k, Pt a) { return {k * a.x, k * a.y}; }

// One person's plan before it becomes YAML.
struct Plan {
  GeneratedPerson who;
  std::vector<Pt> route;
  double start_s = 0;
  int pause_at = -1;
  double pause_s = 0;
  Pt meet{0, 0};  // where on its route it would meet the robot's path
};

// The geometry both the walls and the people are drawn from.
struct Geometry {
  Layout layout = Layout::kAisle;
  double h1 = 1.5;            // half width, robot's aisle
  double h2 = 1.5;            // half width, cross aisle
  double alpha = 90 * kDeg;   // cross aisle direction
  double xc = 5;              // where its centre line meets the robot's
  double x_back = -3, x_end = 12;
  double line_m = 9;          // the robot's task
  Pt u() const { return {std::cos(alpha), std::sin(alpha)}; }
  Pt n() const { return {std::sin(alpha), -std::cos(alpha)}; }  // right of u
  // The point of the cross aisle's line at lateral offset t (along n) where it reaches height y.
  Pt crossAt(double t, double y) const {
    const Pt o = Pt{xc, 0} + t * n();
    const double s = (y - o.y) / u().y;
    return o + s * u();
  }
};

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3f", v);
  return b;
}

std::string points(const std::vector<Pt>& p) {
  std::string s = "[";
  for (std::size_t i = 0; i < p.size(); ++i) s += (i ? ", " : "") + num(p[i].x) + ", " + num(p[i].y);
  return s + "]";
}

// When the robot, driving its line at 0.5 m/s, is at x.
double robotTimeAt(double x) { return kRobotStartup_s + std::max(0.0, x) / kRobotSpeed_m_s; }

// A person walking along the robot's aisle, towards it (opposite) or ahead of it (same direction).
Plan aislePerson(Draw& d, const Geometry& g, bool opposite, double speed, double lateral) {
  Plan p;
  p.who.speed_m_s = speed;
  p.who.heading_deg = opposite ? 180 : 0;
  if (opposite) {
    const double meet_t = d.uniform(4.0, 14.0);  // when they would meet if nobody slowed
    const double meet_x = std::min(g.line_m, kRobotSpeed_m_s * std::max(0.0, meet_t - kRobotStartup_s));
    double start_s = d.uniform(0.0, 3.0);
    double xs = meet_x + speed * (meet_t - start_s);
    const double x_max = g.x_end - 0.5;
    if (xs > x_max) {
      xs = x_max;
      start_s = std::max(0.0, meet_t - (xs - meet_x) / speed);
    }
    xs = std::max(xs, 2.0);
    p.start_s = start_s;
    p.route = {{xs, lateral}, {g.x_back + 0.5, lateral}};
    p.meet = {meet_x, lateral};
  } else {
    // Appears 2.5-4.5 m ahead of where the robot is by then (nobody
    // materialises under its bumper); a stop-and-go leader stops 2-4 m on.
    p.start_s = d.uniform(0.0, 2.0);
    const double xs = kRobotSpeed_m_s * std::max(0.0, p.start_s - kRobotStartup_s) + d.uniform(2.5, 4.5);
    p.route = {{xs, lateral}, {g.x_end - 0.5, lateral}};
    p.meet = {xs + d.uniform(3.0, 5.0), lateral};
  }
  return p;
}

// A person walking the cross aisle, up (+u) or down, through the robot's path.
Plan crossPerson(Draw& d, const Geometry& g, double speed, double lateral) {
  Plan p;
  const bool up = d.chance(0.5);
  p.who.speed_m_s = speed;
  p.who.heading_deg = up ? g.alpha / kDeg : 180.0 - g.alpha / kDeg;
  const Pt through = g.crossAt(lateral, 0.0);
  const Pt from = g.crossAt(lateral, up ? -kFarY_m : kFarY_m);
  const Pt to = g.crossAt(lateral, up ? kFarY_m : -kFarY_m);
  const double far = std::hypot(through.x - from.x, through.y - from.y);
  const double meet_t = robotTimeAt(through.x) + d.uniform(-3.0, 3.0);
  double start_s = d.uniform(0.0, 2.0);
  double dist = speed * (meet_t - start_s);
  if (dist > far) {
    dist = far;
    start_s = std::max(0.0, meet_t - far / speed);
  }
  dist = std::max(dist, std::min(far, g.h1 + 1.0));  // appear outside the robot's aisle
  const Pt dir = (1.0 / far) * (through - from);
  p.start_s = start_s;
  p.route = {through - dist * dir, to};
  p.meet = through;
  return p;
}

// Stop-and-go: a standing pause of 1-3 s on the way: an aisle walker
// 0.5-1.5 m before where they would meet the robot (in its path), a cross
// walker at the mouth of the robot's aisle, 0.3-1.0 m before its wall line.
void addStop(Draw& d, Plan& p, double stop_before_m) {
  const Pt a = p.route.front(), b = p.route.back();
  const double len = std::hypot(b.x - a.x, b.y - a.y);
  const Pt dir = (1.0 / len) * (b - a);
  const double at = (p.meet.x - a.x) * dir.x + (p.meet.y - a.y) * dir.y - stop_before_m;
  const double pause_s = d.uniform(1.0, 3.0);
  if (at < 0.5 || at > len - 0.5) return;  // no room on the route: walks on without stopping
  p.route.insert(p.route.begin() + 1, a + at * dir);
  p.pause_at = 1;
  p.pause_s = pause_s;
}

// The lateral offset range that keeps a body clear of the aisle's walls.
double clampLateral(double v, double half) { return std::clamp(v, -(half - kWallClear_m), half - kWallClear_m); }

// Walls of the layout as YAML list items.
std::string wallsYaml(const Geometry& g) {
  std::string s = "walls:\n";
  if (g.layout == Layout::kAisle) {
    s += "  - points_m: " + points({{g.x_back, -g.h1}, {g.x_end, -g.h1}, {g.x_end, g.h1}, {g.x_back, g.h1}}) +
         "\n    closed: true\n";
    return s;
  }
  // Two aisles crossing: four corner walls, closed at the robot aisle's two ends.
  const double tl = -g.h2, tr = g.h2;  // n points right of u: t = -h2 is the left edge at any height
  const Pt ul = g.crossAt(tl, g.h1), ll = g.crossAt(tl, -g.h1), ur = g.crossAt(tr, g.h1), lr = g.crossAt(tr, -g.h1);
  s += "  - points_m: " + points({g.crossAt(tl, kFarY_m), ul, {g.x_back, g.h1}, {g.x_back, -g.h1}, ll,
                                  g.crossAt(tl, -kFarY_m)}) + "\n";
  s += "  - points_m: " + points({g.crossAt(tr, kFarY_m), ur, {g.x_end, g.h1}, {g.x_end, -g.h1}, lr,
                                  g.crossAt(tr, -kFarY_m)}) + "\n";
  return s;
}

// The x of the robot aisle's end walls, beyond the crossing's corners.
void placeEnds(Geometry& g) {
  double lo = 0, hi = 0;
  for (double t : {-g.h2, g.h2})
    for (double y : {-g.h1, g.h1}) {
      lo = std::min(lo, g.crossAt(t, y).x);
      hi = std::max(hi, g.crossAt(t, y).x);
    }
  g.x_back = std::min(-3.0, lo - 1.0);
  g.x_end = std::max(g.line_m + 3.0, hi + 1.0);
}

// The episode's world file (kept as its spec's description), its world and task.
void finish(Episode& e, const Geometry& g, std::vector<Plan>& plans, const std::string& name, const std::string& how,
            const std::string& spec_name) {
  std::string yaml = "name: " + name + "\n";
  char head[256];
  std::snprintf(head, sizeof head, "description: %s (%s, width %.1f m%s)\n", how.c_str(), toString(g.layout),
                e.width_m,
                g.layout == Layout::kCrossing
                    ? (", cross aisle " + num(e.cross_width_m) + " m at " + num(e.cross_angle_deg) + " deg").c_str()
                    : "");
  yaml += head;
  yaml += "start: {x_m: 0.0, y_m: 0.0, theta_rad: 0.0}\n";
  yaml += wallsYaml(g);
  yaml += "pedestrians:\n";
  for (std::size_t i = 0; i < plans.size(); ++i) {
    auto& p = plans[i];
    p.who.id = "p" + std::to_string(i) + "_" + toString(p.who.behaviour);
    yaml += "  - id: " + p.who.id + "\n";
    yaml += "    speed_m_s: " + num(p.who.speed_m_s) + "\n";
    yaml += "    start_s: " + num(p.start_s) + "\n";
    yaml += "    route_m: " + points(p.route) + "\n";
    if (p.pause_at >= 0) yaml += "    pauses: [{at: " + std::to_string(p.pause_at) + ", s: " + num(p.pause_s) + "}]\n";
    if (p.who.behaviour == Behaviour::kNotReacting) yaml += "    notices_robot: false\n";
    e.people.push_back(p.who);
  }
  e.spec.name = spec_name;
  e.spec.description = yaml;  // the world file (worldYaml)
  e.spec.world = world::loadWorldText(yaml, e.spec.name);
  e.spec.task.kind = sim::ScenarioTask::Kind::kLine;
  e.spec.task.length_m = g.line_m;
  e.spec.task.speed_m_s = kRobotSpeed_m_s;
  e.spec.time_limit_s = kTimeLimit_s;
}

}  // namespace

const char* toString(Behaviour b) {
  switch (b) {
    case Behaviour::kRegular: return "regular";
    case Behaviour::kNotReacting: return "not_reacting";
    case Behaviour::kStopAndGo: return "stop_and_go";
    case Behaviour::kTogether: return "together";
  }
  return "?";
}

const char* toString(Layout l) { return l == Layout::kAisle ? "aisle" : "crossing"; }

Episode generateEpisode(uint64_t run_seed, int index) {
  Episode e;
  e.run_seed = run_seed;
  e.index = index;
  Draw seeder(run_seed * 0x100000001B3ULL + static_cast<uint64_t>(index));
  e.seed = seeder.next();
  Draw d(e.seed);

  Geometry g;
  g.layout = d.chance(0.5) ? Layout::kAisle : Layout::kCrossing;
  const double widths[] = {1.8, 2.4, 3.0, 4.0};
  e.width_m = d.among(widths);
  g.h1 = e.width_m / 2;
  if (g.layout == Layout::kCrossing) {
    const double cross_widths[] = {1.8, 2.4, 3.0};
    e.cross_width_m = d.among(cross_widths);
    g.h2 = e.cross_width_m / 2;
    e.cross_angle_deg = d.uniform(30.0, 150.0);
    g.alpha = e.cross_angle_deg * kDeg;
    g.xc = d.uniform(3.5, 6.0);
    g.line_m = g.xc + 4.0;
    placeEnds(g);
  } else {
    g.line_m = 9.0;
    g.x_back = -3.0;
    g.x_end = g.line_m + 4.0;
  }
  e.layout = g.layout;

  // People: 1 (50 %), 2 (35 %) or 3 (15 %); "together" takes two places.
  const double r = d.uniform(0, 1);
  const int count = r < 0.5 ? 1 : r < 0.85 ? 2 : 3;
  std::vector<Plan> plans;
  for (int k = 0; static_cast<int>(plans.size()) < count && k < 6; ++k) {
    const double b = d.uniform(0, 1);
    Behaviour beh = b < 0.4 ? Behaviour::kRegular : b < 0.65 ? Behaviour::kNotReacting
                  : b < 0.85 ? Behaviour::kStopAndGo : Behaviour::kTogether;
    if (beh == Behaviour::kTogether && static_cast<int>(plans.size()) + 2 > count) beh = Behaviour::kRegular;
    const double speed = d.uniform(0.3, 1.6);
    const bool cross = g.layout == Layout::kCrossing && (plans.empty() || d.chance(0.5));
    const double half = cross ? g.h2 : g.h1;
    // A pair needs room for both side by side: draw the pair's middle, then
    // the first of them half a gap to the left (the partner goes to the right).
    const double pair_room = half - kWallClear_m - kTogetherGap_m / 2;
    const double lateral = beh == Behaviour::kTogether ? d.uniform(-pair_room, pair_room) + kTogetherGap_m / 2
                                                       : clampLateral(d.uniform(-half, half), half);
    Plan p = cross ? crossPerson(d, g, speed, lateral) : aislePerson(d, g, d.chance(0.6), speed, lateral);
    p.who.behaviour = beh;
    if (beh == Behaviour::kStopAndGo) {
      // A cross walker reaches the robot's aisle wall line h1 / sin(alpha) before its centre line.
      const double before = cross ? g.h1 / std::sin(g.alpha) + d.uniform(0.3, 1.0) : d.uniform(0.5, 1.5);
      addStop(d, p, before);
    }
    if (beh == Behaviour::kTogether) {
      // The partner: the same walk, side by side (0.7 m between centres).
      Plan q = p;
      const Pt across = cross ? g.n() : Pt{0.0, 1.0};  // the aisle's lateral axis (the one `lateral` is on)
      const double delta = -kTogetherGap_m;
      for (auto& pt : q.route) pt = pt + delta * across;
      q.meet = q.meet + delta * across;
      plans.push_back(std::move(p));
      plans.push_back(std::move(q));
    } else {
      plans.push_back(std::move(p));
    }
  }

  char head[256];
  std::snprintf(head, sizeof head, "social_arena --seed %llu --episode %d", static_cast<unsigned long long>(run_seed),
                index);
  finish(e, g, plans, "arena_" + std::to_string(run_seed) + "_" + std::to_string(index), head,
         "arena_" + std::to_string(index));
  return e;
}

std::vector<CrossingCase> crossingCases() {
  std::vector<CrossingCase> out;
  for (const double angle : {45.0, 135.0})
    for (const double speed : {1.4, 0.4})
      for (const bool yields : {true, false}) out.push_back({angle, speed, yields});
  return out;
}

std::string CrossingCase::name() const {
  char b[64];
  std::snprintf(b, sizeof b, "cross%.0f_%s_%s", angle_deg, speed_m_s >= 1.0 ? "fast" : "slow",
                yields ? "yields" : "does_not_yield");
  return b;
}

Episode crossingEpisode(const CrossingCase& c) {
  Episode e;
  e.run_seed = 0;
  e.index = -1;
  e.seed = 0;
  Geometry g;
  g.layout = Layout::kCrossing;
  e.width_m = 3.0;
  g.h1 = e.width_m / 2;
  e.cross_width_m = 2.4;
  g.h2 = e.cross_width_m / 2;
  e.cross_angle_deg = c.angle_deg;
  g.alpha = c.angle_deg * kDeg;
  g.xc = 5.0;
  g.line_m = 9.0;
  placeEnds(g);
  e.layout = g.layout;
  // One person on the cross aisle's centre line, walking +u (heading
  // angle_deg relative to the robot's), timed to reach the crossing point
  // when the robot would if nobody slowed.
  Plan p;
  p.who.speed_m_s = c.speed_m_s;
  p.who.heading_deg = c.angle_deg;
  p.who.behaviour = c.yields ? Behaviour::kRegular : Behaviour::kNotReacting;
  const Pt through = g.crossAt(0.0, 0.0), from = g.crossAt(0.0, -kFarY_m), to = g.crossAt(0.0, kFarY_m);
  const double far = std::hypot(through.x - from.x, through.y - from.y);
  const double meet_t = robotTimeAt(through.x);
  p.start_s = std::max(0.0, meet_t - far / c.speed_m_s);
  const double dist = std::max(std::min(far, c.speed_m_s * (meet_t - p.start_s)), std::min(far, g.h1 + 1.0));
  const Pt dir = (1.0 / far) * (through - from);
  p.route = {through - dist * dir, to};
  p.meet = through;
  std::vector<Plan> plans{p};
  finish(e, g, plans, c.name(), "social_arena --crossings, case " + c.name(), c.name());
  return e;
}

std::string worldYaml(const Episode& e) { return e.spec.description; }

}  // namespace inspect::arena
