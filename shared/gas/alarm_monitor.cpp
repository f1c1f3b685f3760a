#include "shared/gas/alarm_monitor.hpp"

#include <cmath>

namespace inspect::gas {

const char* levelName(AlarmLevel l) {
  switch (l) {
    case AlarmLevel::Low: return "LOW";
    case AlarmLevel::High: return "HIGH";
    case AlarmLevel::SensorFault: return "SENSOR_FAULT";
  }
  return "?";
}

AlarmMonitor::AlarmMonitor(const config::GasConfig& cfg) : cfg_(cfg) {
  if (cfg_.channels.size() > kMaxChannels) cfg_.channels.resize(kMaxChannels);
}

double AlarmMonitor::value(int channel) const {
  if (channel < 0 || channel >= channels()) return std::numeric_limits<double>::quiet_NaN();
  return ch_[static_cast<std::size_t>(channel)].value;
}

double AlarmMonitor::filtered(int channel) const {
  if (channel < 0 || channel >= channels()) return std::numeric_limits<double>::quiet_NaN();
  return ch_[static_cast<std::size_t>(channel)].filtered;
}

bool AlarmMonitor::anyHigh() const {
  for (int i = 0; i < channels(); ++i)
    if (ch_[static_cast<std::size_t>(i)].high.active) return true;
  return false;
}

void AlarmMonitor::latch(Latch& l, int ch, AlarmLevel level, const char* fault, bool raise_cond, bool clear_cond,
                         double threshold, double value, double delay_s, double now_s,
                         std::vector<AlarmTransition>& out) {
  if (!l.active) {
    if (!raise_cond) {
      l.pending_since = -1.0;
      return;
    }
    if (l.pending_since < 0.0) l.pending_since = now_s;
    if (now_s - l.pending_since + 1e-9 < delay_s) return;
    l.active = true;
    l.pending_since = -1.0;
    l.cur = AlarmTransition{next_id_++, ch, level, true, value, threshold, fault, now_s, now_s, value};
    out.push_back(l.cur);
    return;
  }
  // Active: track the worst reading and the value now.
  if (!std::isnan(value)) {
    const auto& c = cfg_.channels[static_cast<std::size_t>(ch)];
    if (std::isnan(l.cur.peak) || (c.direction == config::AlarmDirection::Rising ? value > l.cur.peak
                                                                                  : value < l.cur.peak))
      l.cur.peak = value;
  }
  l.cur.value = value;
  if (!clear_cond) {
    l.pending_since = -1.0;
    return;
  }
  if (l.pending_since < 0.0) l.pending_since = now_s;
  if (now_s - l.pending_since + 1e-9 < delay_s) return;
  AlarmTransition t = l.cur;
  t.active = false;
  t.t_s = now_s;
  out.push_back(t);
  l.active = false;
  l.pending_since = -1.0;
}

void AlarmMonitor::step(int i, bool have, uint16_t raw, double now_s, std::vector<AlarmTransition>& out) {
  auto& c = ch_[static_cast<std::size_t>(i)];
  const auto& cfg = cfg_.channels[static_cast<std::size_t>(i)];
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const bool no_data = !have || raw == config::kGasNoData;
  c.value = no_data ? nan : raw * cfg.scale;

  // No data: the sensor dropped out (0xFFFF) or no frames arrive.
  latch(c.nodata, i, AlarmLevel::SensorFault, "no_data", no_data, !no_data, 0.0, c.value, kNoDataDelay_s, now_s,
        out);
  if (no_data) {
    c.raw_since_s = -1.0;  // stuck detection starts over with the next reading
    c.filtered = nan;      // and the filter, and the raise/clear timers of the gas alarms
    c.low.pending_since = c.high.pending_since = -1.0;
    return;                // gas alarms hold their state: no reading, no all-clear
  }
  // First-order low-pass (exact for any frame interval): the thresholds see
  // the noise cut by ~10 instead of single noisy frames.
  if (std::isnan(c.filtered)) {
    c.filtered = c.value;
  } else {
    const double a = 1.0 - std::exp(-std::max(0.0, now_s - c.filtered_t_s) / kFilter_s);
    c.filtered += a * (c.value - c.filtered);
  }
  c.filtered_t_s = now_s;

  // Stuck: a live sensor's reading always moves by a count or more within
  // stuck_s - except at the bottom of its range, where a sensor with zero
  // suppression reads exactly range_min in clean air.
  if (c.raw_since_s < 0.0 || raw != c.last_raw || c.value <= cfg.range_min) {
    c.last_raw = raw;
    c.raw_since_s = now_s;
  }
  const bool stuck = now_s - c.raw_since_s >= cfg.stuck_s;
  latch(c.stuck, i, AlarmLevel::SensorFault, "stuck", stuck, !stuck, 0.0, c.value, 0.0, now_s, out);

  // Out of range: outside the measuring range (an over-range reading still drives the alarms below).
  const bool outside = c.value > cfg.range_max || c.value < cfg.range_min;
  latch(c.range, i, AlarmLevel::SensorFault, "out_of_range", outside, !outside, 0.0, c.value, cfg.min_duration_s,
        now_s, out);
  if (c.stuck.active) {  // a frozen reading can neither raise nor clear a gas alarm
    c.low.pending_since = c.high.pending_since = -1.0;
    return;
  }

  // A1 and A2 with hysteresis: raised beyond the threshold, cleared once back past it by `hysteresis`.
  const double back = cfg.direction == config::AlarmDirection::Rising ? -cfg.hysteresis : cfg.hysteresis;
  const double f = c.filtered;
  latch(c.low, i, AlarmLevel::Low, "", cfg.beyond(f, cfg.alarm_low), !cfg.beyond(f, cfg.alarm_low + back),
        cfg.alarm_low, c.value, cfg.min_duration_s, now_s, out);
  latch(c.high, i, AlarmLevel::High, "", cfg.beyond(f, cfg.alarm_high), !cfg.beyond(f, cfg.alarm_high + back),
        cfg.alarm_high, c.value, cfg.min_duration_s, now_s, out);
}

void AlarmMonitor::update(std::span<const uint16_t> raw, double now_s, std::vector<AlarmTransition>& out) {
  for (int i = 0; i < channels(); ++i) {
    const bool have = static_cast<std::size_t>(i) < raw.size();
    step(i, have, have ? raw[static_cast<std::size_t>(i)] : config::kGasNoData, now_s, out);
  }
}

void AlarmMonitor::noFrames(double now_s, std::vector<AlarmTransition>& out) {
  for (int i = 0; i < channels(); ++i) step(i, false, config::kGasNoData, now_s, out);
}

void AlarmMonitor::active(std::vector<AlarmTransition>& out) const {
  for (int i = 0; i < channels(); ++i) {
    const auto& c = ch_[static_cast<std::size_t>(i)];
    for (const Latch* l : {&c.nodata, &c.stuck, &c.range, &c.low, &c.high})
      if (l->active) out.push_back(l->cur);
  }
}

}  // namespace inspect::gas
