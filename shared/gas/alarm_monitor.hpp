#pragma once
// Gas alarm logic of the robot (docs/gas.md): per channel an A1 (low) and an
// A2 (high) alarm with hysteresis and a minimum duration, and sensor fault
// detection (stuck, out of range, no data). Pure: readings and time in,
// raise/clear transitions out; no clock reads, no allocation per update once
// the output vector has grown.
#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "shared/config/gas_config.hpp"

namespace inspect::gas {

enum class AlarmLevel { Low, High, SensorFault };

/// "LOW", "HIGH", "SENSOR_FAULT".
const char* levelName(AlarmLevel l);

/// One alarm (or sensor fault) being raised or cleared, or in force.
struct AlarmTransition {
  uint64_t id = 0;          // per occurrence; raise and clear share it
  int channel = 0;
  AlarmLevel level = AlarmLevel::Low;
  bool active = true;       // raised (true) or cleared (false)
  double value = 0.0;       // reading at the transition (NaN = no data)
  double threshold = 0.0;   // the level's threshold (0 for faults)
  const char* fault = "";   // SensorFault: "stuck", "out_of_range", "no_data"
  double since_s = 0.0;     // when it was raised
  double t_s = 0.0;         // this transition
  double peak = 0.0;        // worst reading while raised
};

class AlarmMonitor {
 public:
  static constexpr int kMaxChannels = 4;
  /// How long a channel may give no data (0xFFFF or no frames) before the fault.
  static constexpr double kNoDataDelay_s = 0.5;
  /// Time constant of the low-pass filter the thresholds are compared with
  /// (sensor noise / 10 at 100 Hz frames; adds ~0.5 s of delay).
  static constexpr double kFilter_s = 0.5;

  explicit AlarmMonitor(const config::GasConfig& cfg);

  /// One sensor frame's raw gas slots at now_s; appends transitions to `out`.
  void update(std::span<const uint16_t> raw, double now_s, std::vector<AlarmTransition>& out);
  /// No sensor frame arrived (frames stale): every channel is treated as giving no data.
  void noFrames(double now_s, std::vector<AlarmTransition>& out);

  /// Alarms and faults in force (active = true), in channel, level order.
  void active(std::vector<AlarmTransition>& out) const;
  /// Last reading of a channel in its unit; NaN when it gives no data.
  double value(int channel) const;
  /// The low-passed reading the thresholds are compared with; NaN when no data.
  double filtered(int channel) const;
  /// True when any HIGH alarm is in force.
  bool anyHigh() const;
  int channels() const { return static_cast<int>(cfg_.channels.size()); }
  const config::GasConfig& config() const { return cfg_; }

 private:
  /// One latch: a condition that must hold min_duration to raise and its
  /// release condition min_duration to clear.
  struct Latch {
    bool active = false;
    double pending_since = -1.0;  // condition (to raise, or to clear) holding since; < 0 = not
    AlarmTransition cur;          // valid while active
  };
  struct Channel {
    Latch low, high, stuck, range, nodata;
    uint16_t last_raw = 0;
    double raw_since_s = -1.0;    // last_raw unchanged since
    double value = std::numeric_limits<double>::quiet_NaN();     // last reading
    double filtered = std::numeric_limits<double>::quiet_NaN();  // low-passed reading (kFilter_s)
    double filtered_t_s = 0.0;
  };

  void step(int ch, bool have, uint16_t raw, double now_s, std::vector<AlarmTransition>& out);
  void latch(Latch& l, int ch, AlarmLevel level, const char* fault, bool raise_cond, bool clear_cond,
             double threshold, double value, double delay_s, double now_s, std::vector<AlarmTransition>& out);

  config::GasConfig cfg_;
  std::array<Channel, kMaxChannels> ch_{};
  uint64_t next_id_ = 1;
};

}  // namespace inspect::gas
