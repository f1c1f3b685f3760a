#include "shared/util/gnuplot.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace inspect::plot {
std::string quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (c == '\n') out += "\\n";
    else out += c;
  }
  return out + "\"";
}

std::string runScript(const std::string& png_path, const std::string& script) {
  const std::string script_path = png_path + ".gp";
  {
    std::ofstream f(script_path);
    if (!(f << script)) return "cannot write " + script_path;
  }
  FILE* pipe = ::popen(("gnuplot " + quote(script_path) + " 2>&1").c_str(), "r");
  if (!pipe) return "cannot run gnuplot";
  std::string out;
  char buf[512];
  while (std::fgets(buf, sizeof buf, pipe)) out += buf;
  if (::pclose(pipe) != 0) return "gnuplot failed (is gnuplot-nox installed?): " + out.substr(0, 400);
  std::remove(script_path.c_str());
  return "";
}

std::string renderPng(const std::string& png_path, const std::vector<Panel>& panels, int width_px,
                      int panel_height_px) {
  if (panels.empty()) return "nothing to plot";
  std::ostringstream g;
  g.precision(9);
  // Inline data blocks, one per series.
  for (std::size_t p = 0; p < panels.size(); ++p)
    for (std::size_t s = 0; s < panels[p].series.size(); ++s) {
      const auto& se = panels[p].series[s];
      g << "$d" << p << "_" << s << " << EOD\n";
      for (std::size_t i = 0; i < se.x.size() && i < se.y.size(); ++i) {
        if (std::isfinite(se.x[i]) && std::isfinite(se.y[i]))
          g << se.x[i] << " " << se.y[i] << "\n";
        else
          g << "\n";  // a gap
      }
      g << "EOD\n";
    }
  g << "set terminal pngcairo size " << width_px << "," << panel_height_px * static_cast<int>(panels.size())
    << " font 'DejaVu Sans,10' noenhanced\n";  // titles are literal text (ids have underscores)
  g << "set output " << quote(png_path) << "\n";
  g << "set grid\n";
  if (panels.size() > 1) g << "set multiplot layout " << panels.size() << ",1\n";
  for (std::size_t p = 0; p < panels.size(); ++p) {
    const auto& pa = panels[p];
    g << "unset object\n";
    g << "unset label\n";
    for (std::size_t l = 0; l < pa.labels.size(); ++l) {
      const auto& lb = pa.labels[l];
      if (!std::isfinite(lb.x) || !std::isfinite(lb.y)) continue;
      g << "set label " << l + 1 << " " << quote(lb.text) << " at first " << lb.x << ", first " << lb.y
        << " offset 0.4,0.4 font ',8' tc rgb " << quote(lb.color) << " front\n";
    }
    g << "set title " << quote(pa.title) << "\n";
    g << "set xlabel " << quote(pa.xlabel) << "\n";
    g << "set ylabel " << quote(pa.ylabel) << "\n";
    g << "set key " << pa.key << "\n";
    g << "set yrange " << (pa.yrange.empty() ? "[*:*]" : pa.yrange) << "\n";
    if (pa.equal_axes)
      g << "set size ratio -1\n";
    else
      g << "set size noratio\n";
    int obj = 1;
    for (const auto& b : pa.bands)
      g << "set object " << obj++ << " rect from graph 0, first " << b.y0 << " to graph 1, first " << b.y1
        << " fc rgb " << quote(b.color) << " fs solid 0.5 noborder behind\n";
    g << "plot ";
    for (std::size_t s = 0; s < pa.series.size(); ++s) {
      const auto& se = pa.series[s];
      if (s) g << ", ";
      g << "$d" << p << "_" << s << " using 1:2 with " << se.style;
      if (se.style.find("lines") != std::string::npos) g << " lw " << se.width << (se.dashed ? " dt 2" : "");
      if (!se.color.empty()) g << " lc rgb " << quote(se.color);
      g << " title " << quote(se.title);
    }
    if (pa.series.empty()) g << "NaN notitle";
    g << "\n";
  }
  if (panels.size() > 1) g << "unset multiplot\n";
  return runScript(png_path, g.str());
}

}  // namespace inspect::plot
