#pragma once
// Rate adaptation of the robot's camera stream from the receiver's RTCP
// reports (docs/video.md "Rate adaptation"). A pure function of the reports
// and time: the sender feeds it each receiver report about its stream and
// ticks it with every frame; it answers with the bitrate, the frame-rate and
// size level in force and why they last changed.
//
// The rule is the loss-based half of Google Congestion Control
// (draft-ietf-rmcat-gcc-02 section 6) on the report's fraction lost p
// (counted on the wire, before repair):
//   p > 10 %        A <- A (1 - 0.5 p)
//   2 % <= p <= 10 % A held
//   p < 2 %         A <- A x 1.08 per second since the last report
// plus a round-trip guard (the delay half of GCC needs per-packet arrival
// times we do not send back): a report whose RTT exceeds both twice the least
// RTT seen and the least plus `rtt_rise_ms` means a queue is building,
// A <- 0.85 A. Reports that stop coming while the stream runs (feedback lost,
// or the receiver gone) halve A every `report_timeout_s`.
// A is kept within [min_kbps, max_kbps] while the stream is at full frame
// rate and size. When A would fall below min_kbps the stream steps down a
// level instead (level 1: half the frame rate; level 2: also half the width
// and height), at most once per `level_hold_s`; it steps back up (size
// first, then frame rate) when A has climbed to `step_up_ratio` x min_kbps.
#include <cstdint>
#include <optional>
#include <string>

namespace inspect::video {

struct RateSettings {
  bool enabled = true;
  int start_kbps = 2000;
  int min_kbps = 500;
  int max_kbps = 4000;             // (SenderSettings: 0 = the configured bitrate)
  double high_loss = 0.10;         // above: decrease
  double low_loss = 0.02;          // below: increase
  double increase_per_s = 1.08;    // factor per second of reports below low_loss
  double rtt_rise_ms = 50;         // RTT above the least seen by this much (and x2): decrease
  double rtt_decrease = 0.85;
  double report_timeout_s = 3.0;   // no report this long after one came: halve
  int max_level = 2;               // 1: half frame rate; 2: and half size
  double level_hold_s = 2.0;       // least time between level changes
  double step_up_ratio = 1.5;      // A >= this x min_kbps at a reduced level: one level up
};

/// "" or the first setting out of range, named as in config/client.yaml.
std::string validate(const RateSettings& s);

/// What the encoder should do now.
struct RateState {
  int kbps = 0;             // bitrate in force
  int level = 0;            // 0 full; 1 half frame rate; 2 half frame rate and half size
  std::string reason;       // why the rate or level last changed
  uint64_t changed_us = 0;  // when (the caller's clock)
  uint64_t changes = 0;     // how many times it changed
};

class RateController {
 public:
  explicit RateController(RateSettings s = {}, uint64_t now_us = 0);

  /// A receiver report about the stream: fraction lost [0, 1] and, when
  /// the report carried LSR/DLSR, the round trip.
  void onReport(uint64_t now_us, double loss_fraction, std::optional<double> rtt_ms);
  /// Time passes (called with every frame): the report timeout.
  void tick(uint64_t now_us);
  /// The operator set the rate: it becomes the ceiling and the rate in force
  /// (the floor is lowered to it if above), at full frame rate and size.
  void setOperatorRate(uint64_t now_us, int kbps);

  const RateState& state() const { return st_; }
  const RateSettings& settings() const { return s_; }
  /// The frame-rate and size divisors of `level`.
  static int fpsDivisor(int level) { return level >= 1 ? 2 : 1; }
  static int sizeDivisor(int level) { return level >= 2 ? 2 : 1; }

 private:
  void apply(uint64_t now_us, double target_kbps, const std::string& why);

  RateSettings s_;
  RateState st_;
  double target_ = 0;               // A, kbit/s (may dip below min_kbps before a level step)
  uint64_t last_report_us_ = 0;     // 0 = none yet
  uint64_t last_timeout_us_ = 0;
  uint64_t level_changed_us_ = 0;
  double min_rtt_ms_ = -1;
};

}  // namespace inspect::video
