#pragma once
// PNG plots through gnuplot (Debian gnuplot-nox): figures are described as
// data, written as one gnuplot script with inline data blocks, and rendered
// by the gnuplot program. Used by experiments, scenarios and reports.
#include <string>
#include <vector>

namespace inspect::plot {

/// One line or point set.
struct Series {
  std::string title;
  std::vector<double> x;
  std::vector<double> y;
  std::string style = "lines";  // gnuplot style: lines, points, linespoints, ...
  std::string color;            // e.g. "#1f77b4"; empty = gnuplot's default cycle
  int width = 2;
  bool dashed = false;
};

/// A horizontal band shaded between y0 and y1 (e.g. a proxemic zone).
struct Band {
  double y0 = 0, y1 = 0;
  std::string color = "#eeeeee";
  std::string label;
};

/// A text placed at a data point (e.g. a time mark on a path).
struct Label {
  double x = 0, y = 0;
  std::string text;
  std::string color = "#333333";
};

/// One panel of a figure.
struct Panel {
  std::string title;
  std::string xlabel;
  std::string ylabel;
  std::vector<Series> series;
  std::vector<Band> bands;
  std::vector<Label> labels;
  bool equal_axes = false;  // same scale on x and y (trajectories)
  std::string key = "top right";
  std::string yrange;       // gnuplot range, e.g. "[0:*]"; empty = automatic
};

/// A series with its legend title and look (points filled in by the caller).
inline Series series(const std::string& title, const std::string& color, int width = 2, bool dashed = false) {
  Series s;
  s.title = title;
  s.color = color;
  s.width = width;
  s.dashed = dashed;
  return s;
}

/// A panel with its title and axis labels.
inline Panel panel(const std::string& title, const std::string& xlabel, const std::string& ylabel) {
  Panel p;
  p.title = title;
  p.xlabel = xlabel;
  p.ylabel = ylabel;
  return p;
}

/// A gnuplot string literal ("\n" in `s` becomes a line break in the figure).
std::string quote(const std::string& s);

/// Runs a gnuplot `script` that writes `png_path` itself, keeping the script
/// next to it (<png>.gp) until it worked. "" or what went wrong (gnuplot
/// missing, its error). renderPng draws through it; so do the gas maps.
std::string runScript(const std::string& png_path, const std::string& script);

/// Writes `png_path` with the panels stacked vertically. Returns an empty
/// string on success, else what went wrong (gnuplot missing, its error).
std::string renderPng(const std::string& png_path, const std::vector<Panel>& panels, int width_px = 900,
                      int panel_height_px = 450);

}  // namespace inspect::plot
