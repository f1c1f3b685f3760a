#include "pc_server/recording/report_gas.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <iterator>
#include <sstream>

#include "shared/util/number_text.hpp"
#include "pc_server/recording/run_stats.hpp"
#include "shared/util/gnuplot.hpp"
#include "shared/util/number_text.hpp"

namespace inspect::server::report {

using util::fmtFixed;
using util::fmtShort;
namespace fs = std::filesystem;
namespace {

// Colours of the map: pale yellow (low) to dark red (high), as a gnuplot
// palette and interpolated here for the image's own RGBA pixels.
constexpr std::pair<double, unsigned> kMapStops[] = {
    {0.0, 0xffffd4}, {0.25, 0xfee391}, {0.5, 0xfe9929}, {0.75, 0xd7301f}, {1.0, 0x7f0000}};

unsigned mapColor(double frac) {
  frac = std::clamp(frac, 0.0, 1.0);
  for (std::size_t i = 1; i < std::size(kMapStops); ++i) {
    const auto [f1, c1] = kMapStops[i];
    const auto [f0, c0] = kMapStops[i - 1];
    if (frac > f1 && i + 1 < std::size(kMapStops)) continue;
    const double a = (frac - f0) / (f1 - f0);
    unsigned out = 0;
    for (int sh : {16, 8, 0}) {
      const double v0 = (c0 >> sh) & 0xff, v1 = (c1 >> sh) & 0xff;
      out |= static_cast<unsigned>(std::lround(v0 + a * (v1 - v0))) << sh;
    }
    return out;
  }
  return kMapStops[0].second;
}

std::string num(double v) { return util::significant(v, 6); }

// Everything one gas map shows.
struct GasMapFigure {
  const Channel* channel = nullptr;
  const gas::ConcentrationMap* map = nullptr;
  gas::LeakEstimate leak;
  gas::ConcentrationMap::Peak peak;
  std::vector<gas::GasSample> path;  // the samples (positions)
  std::vector<const AlarmSpan*> alarms;
  std::vector<geometry::Segment> walls;
  std::string frame_name;
};


// Cells of the map whose nearest sampled point is behind a wall: the kernel
// does not know walls, so what it spreads through one is hidden.
std::vector<char> behindWalls(const gas::ConcentrationMap& m, const std::vector<gas::GasSample>& path,
                              const std::vector<geometry::Segment>& walls) {
  std::vector<char> hidden(m.cols() * m.rows(), 0);
  if (walls.empty()) return hidden;
  std::vector<std::pair<double, double>> pts;  // the path thinned to ~0.1 m
  for (const auto& p : path)
    if (pts.empty() || std::hypot(p.x_m - pts.back().first, p.y_m - pts.back().second) >= 0.1) pts.emplace_back(p.x_m, p.y_m);
  for (std::size_t r = 0; r < m.rows(); ++r)
    for (std::size_t c = 0; c < m.cols(); ++c) {
      if (!m.hasData(c, r)) continue;
      const double x = m.cellX(c), y = m.cellY(r);
      double best = std::numeric_limits<double>::infinity(), bx = x, by = y;
      for (const auto& [px, py] : pts)
        if (const double d = (px - x) * (px - x) + (py - y) * (py - y); d < best) best = d, bx = px, by = py;
      hidden[r * m.cols() + c] =
          std::any_of(walls.begin(), walls.end(), [&](const geometry::Segment& w) { return geometry::segmentsCross({{x, y}, {bx, by}}, w); });
    }
  return hidden;
}

// Alarm levels 1-3 (A1, A2, sensor fault): points, and darker for text on the map.
constexpr const char* kLevelColor[] = {"#999999", "#ff9f1c", "#e00000", "#8e44ad"};
constexpr const char* kLabelColor[] = {"#555555", "#8a4b00", "#a00000", "#5b2370"};

/// The figure's data blocks: the map's cells as coloured pixels (hidden behind walls, faded
/// where samples are few), the path, the walls and each alarm level's points.
void writeMapData(std::ostringstream& g, const GasMapFigure& f, double lo, double hi) {
  const gas::ConcentrationMap& m = *f.map;
  const Channel& ch = *f.channel;
  const std::vector<char> hidden = behindWalls(m, f.path, f.walls);
  g << "$img << EOD\n";
  for (std::size_t r = 0; r < m.rows(); ++r) {
    for (std::size_t c = 0; c < m.cols(); ++c) {
      const double v = m.value(c, r);
      unsigned rgb = 0xffffff, alpha = 0;
      if (std::isfinite(v) && !hidden[r * m.cols() + c]) {
        const double frac = (v - lo) / (hi - lo);
        rgb = mapColor(ch.falling ? 1.0 - frac : frac);
        alpha = static_cast<unsigned>(std::lround(70 + 185 * m.coverage(c, r)));  // faded where samples are few
      }
      g << num(m.cellX(c)) << ' ' << num(m.cellY(r)) << ' ' << (rgb >> 16) << ' ' << ((rgb >> 8) & 0xff) << ' '
        << (rgb & 0xff) << ' ' << alpha << '\n';
    }
    g << '\n';
  }
  g << "EOD\n$path << EOD\n";
  for (std::size_t i : sampleIndices(f.path.size(), kMaxPoints)) {
    if (i && std::hypot(f.path[i].x_m - f.path[i - 1].x_m, f.path[i].y_m - f.path[i - 1].y_m) > kMaxOdometryStepM) g << '\n';
    g << num(f.path[i].x_m) << ' ' << num(f.path[i].y_m) << '\n';
  }
  g << "EOD\n$walls << EOD\n";
  for (const auto& w : f.walls) g << num(w.a.x) << ' ' << num(w.a.y) << '\n' << num(w.b.x) << ' ' << num(w.b.y) << "\n\n";
  g << "EOD\n";
  for (int lv = 1; lv <= 3; ++lv) {
    g << "$alarm" << lv << " << EOD\n";
    int labelled = 0;
    for (const AlarmSpan* a : f.alarms) {
      if (a->raise.level() != lv || !std::isfinite(a->x)) continue;
      std::string text = fmtShort(a->raised_t, 0) + " s";
      if (lv == v1::GasAlarm::SENSOR_FAULT) text += " " + a->raise.fault();
      else if (std::isfinite(a->raise.value())) text += " " + gasValue(a->raise.value());
      g << num(a->x) << ' ' << num(a->y) << ' ' << plot::quote(++labelled <= 12 ? text : "") << '\n';
    }
    g << "EOD\n";
  }

}

/// The terminal, the title (channel, lag compensation, leak estimate), the axes and the colour bar.
void writeMapAxes(std::ostringstream& g, const std::string& png_path, const GasMapFigure& f, double lo, double hi) {
  const Channel& ch = *f.channel;
  const gas::Bounds& b = f.map->bounds();
  const int width_px = 1000;
  const double aspect = (b.y_max_m - b.y_min_m) / (b.x_max_m - b.x_min_m);
  const int height_px = static_cast<int>(std::clamp(760.0 * aspect + 230.0, 480.0, 1400.0));
  g << "set terminal pngcairo size " << width_px << "," << height_px << " font 'DejaVu Sans,10' noenhanced\n";
  g << "set encoding utf8\nset output " << plot::quote(png_path) << "\n";
  const std::string what = ch.known ? ch.name + (ch.gas.empty() ? "" : " (" + ch.gas + ")") : ch.name;
  std::string title = what + " concentration" + (ch.unit.empty() ? "" : ", " + ch.unit) + " - " + f.frame_name + "\n";
  title += (ch.tau_s() > 0 ? "lag-compensated (t90 " + fmtShort(ch.t90_s, 1) + " s), " : "no lag compensation (t90 unknown), ");
  title += "Gaussian kernel 0.45 m; faded = few samples, hatched = no data\n";
  title += f.leak.found ? "leak source estimate (" + fmtFixed(f.leak.x_m, 2) + ", " + fmtFixed(f.leak.y_m, 2) + ") m \u00b1 " +
                              fmtShort(f.leak.radius95_m, 2) + " m (95 %)"
                        : "no leak source estimate: " + f.leak.reason;
  g << "set title " << plot::quote(title) << "\n";
  g << "set xlabel 'x (m)'\nset ylabel 'y (m)'\n";
  g << "set size ratio -1\nset grid front lc rgb '#bbbbbb' lw 0.5\n";
  g << "set xrange [" << num(b.x_min_m) << ":" << num(b.x_max_m) << "]\n";
  g << "set yrange [" << num(b.y_min_m) << ":" << num(b.y_max_m) << "]\n";
  g << "set key outside bottom center horizontal maxrows 2 samplen 2\n";
  g << "set palette defined (";
  for (std::size_t k = 0; k < std::size(kMapStops); ++k) {  // falling: reversed, low = red
    const auto& stop = kMapStops[ch.falling ? std::size(kMapStops) - 1 - k : k];
    char col[16];
    std::snprintf(col, sizeof col, "#%06x", stop.second);
    g << (k ? ", " : "") << (ch.falling ? 1.0 - stop.first : stop.first) << " '" << col << "'";
  }
  g << ")\n";
  g << "set cbrange [" << num(lo) << ":" << num(hi) << "]\n";
  g << "set cblabel " << plot::quote(ch.name + (ch.unit.empty() ? "" : " (" + ch.unit + ")")) << "\n";
  for (const auto& [name, th] : {std::pair{"A1", ch.alarm_low}, std::pair{"A2", ch.alarm_high}})
    if (std::isfinite(th) && th >= lo && th <= hi) g << "set cbtics add (" << plot::quote(std::string(name) + " " + gasValue(th)) << " " << num(th) << ")\n";
  g << "set colorbox user origin graph 1.02, graph 0 size character 2, graph 1\nset rmargin 14\n";
  g << "set object 1 rectangle from graph 0, graph 0 to graph 1, graph 1 behind fc rgb '#b0b0b0' fs pattern 5 noborder\n";
}

std::string gasMapScript(const std::string& png_path, const GasMapFigure& f) {
  const Channel& ch = *f.channel;
  const gas::ConcentrationMap& m = *f.map;
  // Colour range: the map's values, stretched to the warning threshold so that
  // readings below A1 never look alarming; falling channels run the other way.
  auto [lo, hi] = m.valueRange();
  if (ch.falling && std::isfinite(ch.alarm_low)) lo = std::min(lo, ch.alarm_low);
  if (!ch.falling && std::isfinite(ch.alarm_low)) hi = std::max(hi, ch.alarm_low);
  if (!std::isfinite(lo) || !std::isfinite(hi)) lo = 0.0, hi = 1.0;
  if (!(hi - lo > 1e-9)) hi = lo + 1.0;

  std::ostringstream g;
  g.precision(7);
  writeMapData(g, f, lo, hi);
  writeMapAxes(g, png_path, f, lo, hi);
  int label = 1;
  auto text = [&](double x, double y, const std::string& t, const std::string& color, const std::string& place) {
    g << "set label " << label++ << " " << plot::quote(t) << " at " << num(x) << "," << num(y) << " " << place
      << " font ',9' tc rgb '" << color << "' boxed front\n";
  };
  g << "set style textbox opaque fc rgb '#33ffffff' noborder margins 1.5,1\n";  // labels stay legible on the map
  if (f.peak.valid)
    text(f.peak.x_m, f.peak.y_m, ch.withUnit(gasValue(f.peak.value)), "#000000", "left offset 1.2,-0.8");
  if (f.leak.found)  // under the circle, clear of the peak's label
    text(f.leak.x_m, f.leak.y_m - f.leak.radius95_m, "leak \u00b1" + fmtShort(f.leak.radius95_m, 2) + " m", "#0b3d91",
         "center offset 0,-0.9");

  auto block = [&](const std::string& name, const std::vector<std::pair<double, double>>& pts) {
    g << "$" << name << " << EOD\n";
    for (const auto& [x, y] : pts) g << num(x) << ' ' << num(y) << '\n';
    g << "EOD\n";
  };
  block("cbar", {{kNaN, kNaN}});
  if (!f.path.empty()) block("start", {{f.path.front().x_m, f.path.front().y_m}});
  if (f.peak.valid) block("peak", {{f.peak.x_m, f.peak.y_m}});
  if (f.leak.found) {
    block("leak", {{f.leak.x_m, f.leak.y_m}});
    std::vector<std::pair<double, double>> circle;
    for (int i = 0; i <= 96; ++i) {
      const double a = 2 * 3.14159265358979323846 * i / 96;
      circle.emplace_back(f.leak.x_m + f.leak.radius95_m * std::cos(a), f.leak.y_m + f.leak.radius95_m * std::sin(a));
    }
    block("circle", circle);
  }

  g << "plot $img using 1:2:3:4:5:6 with rgbalpha notitle";
  g << ", $cbar using 1:2:(" << num(lo) << ") with points pt 5 ps 0 lc palette notitle";  // makes the colour bar
  if (!f.walls.empty()) g << ", $walls using 1:2 with lines lw 3 lc rgb '#000000' title 'walls'";
  g << ", $path using 1:2 with lines lw 1.2 lc rgb '#3a3a3a' title 'path'";
  if (!f.path.empty()) g << ", $start using 1:2 with points pt 9 ps 1.8 lc rgb '#2ca02c' title 'start'";
  const char* level_title[] = {"", "alarm A1 raised", "alarm A2 raised", "sensor fault"};
  for (int lv = 1; lv <= 3; ++lv) {
    const bool any = std::any_of(f.alarms.begin(), f.alarms.end(),
                                 [&](const AlarmSpan* a) { return a->raise.level() == lv && std::isfinite(a->x); });
    if (!any) continue;
    g << ", $alarm" << lv << " using 1:2 with points pt 7 ps 1.5 lc rgb '" << kLevelColor[lv] << "' title "
      << plot::quote(level_title[lv]);
    g << ", $alarm" << lv << " using 1:2 with points pt 6 ps 1.5 lc rgb '#000000' notitle";
    g << ", $alarm" << lv << " using 1:2:3 with labels offset 0.8,0.8 left font ',8' tc rgb '" << kLabelColor[lv]
      << "' boxed notitle";
  }
  if (f.peak.valid)
    g << ", $peak using 1:2 with points pt 12 ps 2.2 lw 2 lc rgb '#000000' title " << plot::quote(ch.falling ? "map lowest" : "map peak");
  if (f.leak.found) {
    g << ", $leak using 1:2 with points pt 2 ps 2.5 lw 3 lc rgb '#0b3d91' title 'leak estimate'";
    g << ", $circle using 1:2 with lines lw 2 dt 2 lc rgb '#0b3d91' title '95 % region'";
  }
  g << "\n";
  return g.str();
}


// A file-name-safe version of a channel name.
std::string fileSafe(const std::string& name) {
  std::string out;
  for (char c : name) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_') ? c : '_';
  return out.empty() ? "gas" : out;
}


}  // namespace

// Draws gas_map_<name>.png for every channel with data (one shared extent:
// the path, grown by 2 m, and the site map) and estimates each leak source.
std::vector<GasMapOutcome> gasMaps(const RunReportInput& in, const Frame& frame, const std::vector<Channel>& channels,
                                   const std::vector<AlarmSpan>& spans, const std::string& report_dir,
                                   RunReportResult& result, PlotOutcome& plots) {
  std::vector<GasMapOutcome> out;
  std::vector<std::vector<gas::GasSample>> samples(channels.size());
  constexpr double kInf = std::numeric_limits<double>::infinity();
  gas::Bounds bounds{kInf, kInf, -kInf, -kInf};
  auto grow = [&](double x0, double y0, double x1, double y1) {
    bounds = {std::min(bounds.x_min_m, x0), std::min(bounds.y_min_m, y0), std::max(bounds.x_max_m, x1),
              std::max(bounds.y_max_m, y1)};
  };
  for (const auto& ch : channels) {
    if (!ch.samples) continue;
    samples[static_cast<std::size_t>(ch.index)] = gasSamples(in, frame, ch.index);
    const gas::Bounds b = gas::boundsAround(samples[static_cast<std::size_t>(ch.index)], 2.0);
    if (b.valid()) grow(b.x_min_m, b.y_min_m, b.x_max_m, b.y_max_m);
  }
  std::vector<geometry::Segment> walls;
  gas::LeakOptions options;
  if (frame.world)
    for (const auto& w : in.walls) {
      if (!std::isfinite(w.a.x + w.a.y + w.b.x + w.b.y)) continue;
      walls.push_back(w);
      options.walls.push_back(w);
      grow(std::min(w.a.x, w.b.x) - 0.2, std::min(w.a.y, w.b.y) - 0.2, std::max(w.a.x, w.b.x) + 0.2,
           std::max(w.a.y, w.b.y) + 0.2);
    }
  if (!bounds.valid()) return out;
  gas::MapOptions map_options;
  map_options.max_cells = 250'000;  // a large site gets coarser cells, not a huge PNG script

  for (const auto& ch : channels) {
    if (!ch.samples) continue;
    const auto& raw = samples[static_cast<std::size_t>(ch.index)];
    GasMapOutcome o;
    const auto map = gas::ConcentrationMap::build(gas::compensateLag(raw, ch.tau_s()), bounds, map_options);
    options.falling = ch.falling;
    // A leak worth locating raised the channel to its A1 level at least once;
    // below it the "plume" is noise, cross-sensitivity or a stuck sensor.
    // With the robot's alarm events in the run: an A1 or A2 alarm raised on
    // the channel (filtered, minimum duration: not a noise spike, not a stuck
    // reading). Without any (older runs): the readings' extreme.
    bool any_alarms = false, raised = false;
    for (const auto& [t, a] : in.gas_alarms) {
      any_alarms = true;
      raised |= static_cast<int>(a.channel()) == ch.index && a.active() &&
                (a.level() == v1::GasAlarm::LOW || a.level() == v1::GasAlarm::HIGH);
    }
    const bool reached_a1 = !ch.known || std::isnan(ch.alarm_low) ||
                            (any_alarms ? raised : (ch.falling ? ch.min <= ch.alarm_low : ch.max >= ch.alarm_low));
    if (reached_a1) {
      o.leak = gas::estimateLeak(raw, ch.tau_s(), ch.background, bounds, options);
    } else {
      o.leak.found = false;
      o.leak.reason = "the readings never reached A1 (" +
                      ch.withUnit(gasValue(ch.falling ? ch.min : ch.max)) + (ch.falling ? " > " : " < ") +
                      ch.withUnit(gasValue(ch.alarm_low)) + ")";
    }
    o.peak = map.peak(ch.falling);
    auto& r = o.result;
    r.channel = ch.name;
    r.found = o.leak.found;
    if (r.found) r.x_m = o.leak.x_m, r.y_m = o.leak.y_m, r.radius95_m = o.leak.radius95_m;
    r.peak_x_m = o.peak.valid ? o.peak.x_m : kNaN;
    r.peak_y_m = o.peak.valid ? o.peak.y_m : kNaN;
    r.max_value = ch.max;
    r.mean_value = ch.mean;
    r.unit = ch.unit;
    r.note = o.leak.reason;
    if (ch.tau_s() <= 0.0)
      r.note += std::string(r.note.empty() ? "" : "; ") + "sensor response time unknown: its lag is not undone";

    o.file = "gas_map_" + fileSafe(ch.name) + ".png";
    GasMapFigure fig;
    fig.channel = &ch;
    fig.map = &map;
    fig.leak = o.leak;
    fig.peak = o.peak;
    fig.path = raw;
    fig.walls = walls;
    fig.frame_name = frame.name(in.map_name);
    for (const auto& a : spans)
      if (static_cast<int>(a.raise.channel()) == ch.index && std::isfinite(a.raised_t)) fig.alarms.push_back(&a);
    const std::string path = (fs::path(report_dir) / o.file).string();
    const std::string err = plot::runScript(path, gasMapScript(path, fig));
    std::error_code ec;
    if (err.empty()) {
      result.pngs.push_back(path);
      plots.drawn.emplace_back(o.file, ch.name + " concentration map (" + (ch.tau_s() > 0 ? "lag-compensated, " : "") +
                                           "kernel 0.45 m) with the path, " + (walls.empty() ? "" : "walls, ") +
                                           "alarm raise points, the map's peak and the leak estimate with its 95 % circle");
    } else {
      fs::remove(path + ".gp", ec);
      fs::remove(path, ec);
      plots.notes.push_back(o.file + " not drawn: " + err);
    }
    result.leaks.push_back(r);
    out.push_back(std::move(o));
  }
  return out;
}

}  // namespace inspect::server::report
