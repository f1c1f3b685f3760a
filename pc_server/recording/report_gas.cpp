#include "pc_server/recording/report_gas.hpp"

#include <algorithm>
#include <cstdio>
#include <tuple>

#include "shared/util/number_text.hpp"
#include "shared/util/number_text.hpp"

namespace inspect::server::report {

using util::fmtFixed;
using util::fmtShort;

std::string gasValue(double v) { return util::significant(v, 4); }


// Channel descriptions and NaN-free figures for every gas slot seen in the telemetry.
std::vector<Channel> gasChannels(const RunReportInput& in) {
  std::size_t n = in.gas_channels.size();
  for (const auto& t : in.telemetry) n = std::max(n, static_cast<std::size_t>(t.gas_size()));
  std::vector<Channel> out(n);
  std::vector<double> sums(n, 0.0);
  for (std::size_t c = 0; c < n; ++c) {
    Channel& ch = out[c];
    ch.index = static_cast<int>(c);
    ch.name = "gas" + std::to_string(c);
    if (c < in.gas_channels.size()) {
      const auto& g = in.gas_channels[c];
      ch.known = true;
      if (!g.name().empty()) ch.name = g.name();
      ch.gas = g.gas();
      ch.unit = g.unit();
      ch.t90_s = g.t90_s();
      ch.background = g.background();
      ch.falling = g.falling();
      if (g.alarm_low() != 0.0 || g.alarm_high() != 0.0) ch.alarm_low = g.alarm_low(), ch.alarm_high = g.alarm_high();
    }
  }
  for (const auto& t : in.telemetry)
    for (int c = 0; c < t.gas_size(); ++c) {
      const double v = t.gas(c);
      if (!std::isfinite(v)) continue;
      Channel& ch = out[static_cast<std::size_t>(c)];
      ch.min = ch.samples ? std::min(ch.min, v) : v;
      ch.max = ch.samples ? std::max(ch.max, v) : v;
      sums[static_cast<std::size_t>(c)] += v;
      ++ch.samples;
    }
  for (std::size_t c = 0; c < n; ++c)
    if (out[c].samples) out[c].mean = sums[c] / static_cast<double>(out[c].samples);
  return out;
}

// One line of a Markdown table cell: no pipes, no line breaks.
std::string cell(std::string s) {
  std::string out;
  for (char c : s) {
    if (c == '|') out += "\\|";
    else out += (c == '\n' || c == '\r') ? ' ' : c;
  }
  return out;
}


Frame reportFrame(const RunReportInput& in) {
  if (!in.have_map) return {};
  return {true, in.start_x_m, in.start_y_m, in.start_theta_rad};
}

double runTime(const std::vector<v1::Telemetry>& tel, std::size_t i) {
  return static_cast<double>(static_cast<int64_t>(tel[i].robot_time_us()) - static_cast<int64_t>(tel.front().robot_time_us())) * 1e-6;
}

// One channel's readings where the sensor inlet was, in the report frame.
std::vector<gas::GasSample> gasSamples(const RunReportInput& in, const Frame& f, int channel) {
  std::vector<gas::GasSample> out;
  for (std::size_t i = 0; i < in.telemetry.size(); ++i) {
    const auto& t = in.telemetry[i];
    if (channel >= t.gas_size() || !std::isfinite(t.gas(channel))) continue;
    const auto& p = t.pose();
    const double c = std::cos(p.theta_rad()), s = std::sin(p.theta_rad());
    const auto [x, y] = f.point(p.x_m() + c * in.gas_inlet_x_m - s * in.gas_inlet_y_m,
                                p.y_m() + s * in.gas_inlet_x_m + c * in.gas_inlet_y_m);
    out.push_back({runTime(in.telemetry, i), x, y, t.gas(channel)});
  }
  return out;
}


std::string levelName(v1::GasAlarm::Level l) {
  switch (l) {
    case v1::GasAlarm::LOW: return "A1 (low)";
    case v1::GasAlarm::HIGH: return "A2 (high)";
    case v1::GasAlarm::SENSOR_FAULT: return "sensor fault";
    default: return "unspecified";
  }
}

std::vector<AlarmSpan> alarmSpans(const RunReportInput& in, const Frame& f) {
  std::vector<AlarmSpan> spans;
  auto where = [&](AlarmSpan& a, const v1::GasAlarm& g) {
    if (!g.has_pose()) return;
    std::tie(a.x, a.y) = f.point(g.pose().x_m(), g.pose().y_m());
  };
  for (const auto& tg : in.gas_alarms) {
    // Not a structured binding: clang 14 cannot capture one in the lambda below.
    const auto& t = tg.first;
    const auto& g = tg.second;
    if (g.active()) {
      AlarmSpan a;
      a.raise = g;
      a.raised_t = t;
      a.peak = g.peak();
      where(a, g);
      spans.push_back(std::move(a));
      continue;
    }
    auto open = std::find_if(spans.rbegin(), spans.rend(), [&](const AlarmSpan& a) {
      return a.raise.id() == g.id() && a.raise.channel() == g.channel() && std::isnan(a.cleared_t);
    });
    if (open != spans.rend()) {
      open->cleared_t = t;
      if (std::isfinite(g.peak())) open->peak = g.peak();
      continue;
    }
    AlarmSpan a;  // cleared, raised before the recording began
    a.raise = g;
    a.cleared_t = t;
    a.peak = g.peak();
    where(a, g);
    spans.push_back(std::move(a));
  }
  std::stable_sort(spans.begin(), spans.end(), [](const AlarmSpan& a, const AlarmSpan& b) {
    return (std::isnan(a.raised_t) ? -1.0 : a.raised_t) < (std::isnan(b.raised_t) ? -1.0 : b.raised_t);
  });
  return spans;
}

std::string point(double x, double y) {
  return std::isfinite(x) && std::isfinite(y) ? "(" + fmtFixed(x, 2) + ", " + fmtFixed(y, 2) + ")" : "-";
}

// The summary's gas section: channels, alarms with durations and time in
// alarm, and the leak-source estimates.
void writeGas(std::ostream& md, const RunReportInput& in, const Frame& frame, const std::vector<Channel>& channels,
              const std::vector<AlarmSpan>& spans, const std::vector<GasMapOutcome>& maps) {
  const bool any = std::any_of(channels.begin(), channels.end(), [](const Channel& c) { return c.samples > 0; });
  if (!any && spans.empty() && in.gas_channels.empty()) return;
  md << "## Gas\n\n";
  const std::string where = frame.name(in.map_name);
  if (any) {
    md << "| channel | gas | readings | min | max | mean | map peak at (m) | leak source (m, 95 %) |\n"
          "| --- | --- | --- | --- | --- | --- | --- | --- |\n";
    std::size_t k = 0;
    for (const auto& ch : channels) {
      if (!ch.samples) continue;
      const GasMapOutcome* m = k < maps.size() && maps[k].result.channel == ch.name ? &maps[k++] : nullptr;
      md << "| " << cell(ch.name) << " | " << (ch.gas.empty() ? "-" : cell(ch.gas)) << " | " << ch.samples << " | " << ch.withUnit(gasValue(ch.min))
         << " | " << ch.withUnit(gasValue(ch.max)) << " | " << ch.withUnit(gasValue(ch.mean)) << " | ";
      if (m && m->peak.valid) md << point(m->peak.x_m, m->peak.y_m) << " " << ch.withUnit(gasValue(m->peak.value));
      else md << "-";
      md << " | ";
      if (m && m->leak.found) md << point(m->leak.x_m, m->leak.y_m) << " +- " << fmtFixed(m->leak.radius95_m, 2);
      else md << "not found";
      md << " |\n";
    }
    md << "\nPositions are in the " << where << "; the map peak is the highest cell of the lag-compensated map"
       << " (lowest for falling channels such as O2).\n\n";
  }

  const double end_t = in.telemetry.empty() ? (in.gas_alarms.empty() ? 0.0 : in.gas_alarms.back().first)
                                            : runTime(in.telemetry, in.telemetry.size() - 1);
  auto nameOf = [&](const v1::GasAlarm& a) {
    if (!a.channel_name().empty()) return a.channel_name();
    return a.channel() < channels.size() ? channels[a.channel()].name : "gas" + std::to_string(a.channel());
  };
  md << "### Gas alarms\n\n";
  if (spans.empty()) md << "No gas alarms.\n\n";
  else {
    md << "| raised (s) | cleared (s) | duration | channel | level | value at raise | threshold | peak | raised at (m) |\n"
          "| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
    for (const auto& a : spans) {
      const auto& g = a.raise;
      const std::string unit = g.unit().empty() && g.channel() < channels.size() ? channels[g.channel()].unit : g.unit();
      auto withUnit = [&](double v) { return std::isfinite(v) ? gasValue(v) + (unit.empty() ? "" : " " + unit) : "-"; };
      std::string duration;
      if (std::isnan(a.raised_t)) duration = "raised before the recording";
      else if (std::isnan(a.cleared_t)) duration = "still active at end (" + fmtFixed(end_t - a.raised_t, 1) + " s so far)";
      else duration = fmtFixed(a.cleared_t - a.raised_t, 1) + " s";
      std::string level = levelName(g.level());
      if (g.level() == v1::GasAlarm::SENSOR_FAULT && !g.fault().empty()) level += ": " + g.fault();
      md << "| " << (std::isnan(a.raised_t) ? "-" : fmtFixed(a.raised_t, 1)) << " | "
         << (std::isnan(a.cleared_t) ? "-" : fmtFixed(a.cleared_t, 1)) << " | " << duration << " | " << cell(nameOf(g))
         << " | " << cell(level) << " | " << (g.active() ? withUnit(g.value()) : "-") << " | "
         << (g.level() == v1::GasAlarm::SENSOR_FAULT ? "-" : withUnit(g.threshold())) << " | " << withUnit(a.peak) << " | "
         << (g.active() ? point(a.x, a.y) : "-") << " |\n";
    }
    md << "\n";
    // Time in alarm per channel and level (open alarms count to the end of the run).
    std::vector<std::tuple<std::string, int, int, double, bool>> totals;  // channel, level, count, seconds, open
    for (const auto& a : spans) {
      const std::string ch = nameOf(a.raise);
      const int lv = a.raise.level();
      auto it = std::find_if(totals.begin(), totals.end(), [&](const auto& t) { return std::get<0>(t) == ch && std::get<1>(t) == lv; });
      if (it == totals.end()) it = totals.insert(totals.end(), {ch, lv, 0, 0.0, false});
      const double t0 = std::isnan(a.raised_t) ? 0.0 : a.raised_t, t1 = std::isnan(a.cleared_t) ? end_t : a.cleared_t;
      std::get<2>(*it) += 1;
      std::get<3>(*it) += std::max(0.0, t1 - t0);
      std::get<4>(*it) = std::get<4>(*it) || std::isnan(a.cleared_t);
    }
    std::sort(totals.begin(), totals.end(), [](const auto& a, const auto& b) {
      return std::tie(std::get<0>(a), std::get<1>(a)) < std::tie(std::get<0>(b), std::get<1>(b));
    });
    md << "Time in alarm (an alarm still active counts to the end of the run, " << fmtFixed(end_t, 1) << " s):\n\n"
       << "| channel | level | alarms | total time |\n| --- | --- | --- | --- |\n";
    for (const auto& [ch, lv, count, secs, open] : totals)
      md << "| " << cell(ch) << " | " << levelName(static_cast<v1::GasAlarm::Level>(lv)) << " | " << count << " | "
         << fmtFixed(secs, 1) << " s" << (open ? " (still active at end)" : "") << " |\n";
    md << "\n";
  }

  if (!maps.empty()) {
    md << "### Leak-source estimates\n\n";
    for (const auto& m : maps) {
      const auto& e = m.leak;
      const auto& r = m.result;
      md << "- **" << r.channel << "**: ";
      if (e.found) {
        md << "leak source at " << point(e.x_m, e.y_m) << " m +- " << fmtFixed(e.radius95_m, 2)
           << " m (95 %), " << where << "; plume length scale " << fmtShort(e.length_m, 2)
           << " m, modelled peak " << gasValue(e.peak_signal) << (r.unit.empty() ? "" : " " + r.unit)
           << " above background at " << (e.snr < 1000 ? fmtShort(e.snr, 0) + " x" : "over 1000 x") << " the sensor noise";
        if (!r.note.empty()) md << ". Note: " << r.note;
      } else {
        md << "no source estimate: " << r.note;
      }
      md << ".\n";
    }
    md << "\nThe estimate fits a peaked plume, seen through the sensor's lag along the recorded path, to the raw "
          "readings; the circle holds 95 % of the resulting probability (docs/gas-maps.md).\n\n";
  }
}

}  // namespace inspect::server::report
