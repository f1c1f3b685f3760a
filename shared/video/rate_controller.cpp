#include "shared/video/rate_controller.hpp"

#include <algorithm>
#include <cmath>

#include "shared/util/number_text.hpp"

namespace inspect::video {

using util::fmtFixed;
using util::fmtShort;

namespace {
// Time since `then`; 0 when the clock reads earlier (reports and frames come from two threads).
uint64_t since(uint64_t now_us, uint64_t then_us) { return now_us > then_us ? now_us - then_us : 0; }
}  // namespace

std::string validate(const RateSettings& s) {
  const auto range = [](const char* key, double v, double lo, double hi) -> std::string {
    if (v >= lo && v <= hi) return {};
    return std::string("video.adapt.") + key + ": " + fmtShort(v) + " out of range [" + fmtShort(lo) + ", " +
           fmtShort(hi) + "]";
  };
  for (const auto& why : {range("min_kbps", s.min_kbps, 50, 50000), range("max_kbps", s.max_kbps, 50, 50000),
                          range("high_loss", s.high_loss, 0.01, 1), range("low_loss", s.low_loss, 0, s.high_loss),
                          range("increase_per_s", s.increase_per_s, 1, 2), range("rtt_rise_ms", s.rtt_rise_ms, 1, 10000),
                          range("rtt_decrease", s.rtt_decrease, 0.1, 1), range("report_timeout_s", s.report_timeout_s, 0.5, 60),
                          range("max_level", s.max_level, 0, 2), range("level_hold_s", s.level_hold_s, 0, 60),
                          range("step_up_ratio", s.step_up_ratio, 1.05, 10)})
    if (!why.empty()) return why;
  if (s.min_kbps > s.max_kbps)
    return "video.adapt.min_kbps: " + std::to_string(s.min_kbps) + " above max_kbps " + std::to_string(s.max_kbps);
  return {};
}

RateController::RateController(RateSettings s, uint64_t now_us) : s_(s) {
  target_ = s_.enabled ? std::clamp(s_.start_kbps, s_.min_kbps, s_.max_kbps) : s_.start_kbps;
  st_.kbps = static_cast<int>(std::lround(target_));
  st_.reason = "start";
  st_.changed_us = now_us;
  level_changed_us_ = now_us;
}

void RateController::apply(uint64_t now_us, double target_kbps, const std::string& why) {
  target_ = target_kbps;
  int level = st_.level;
  std::string reason = why;
  const bool may_step = since(now_us, level_changed_us_) >= static_cast<uint64_t>(s_.level_hold_s * 1e6);
  if (target_ < s_.min_kbps && level < s_.max_level && may_step) {
    ++level;
    reason += level == 1 ? "; below " + std::to_string(s_.min_kbps) + " kbit/s: frame rate halved"
                         : "; below " + std::to_string(s_.min_kbps) + " kbit/s: size halved";
    target_ = s_.min_kbps;
  } else if (level > 0 && target_ >= s_.step_up_ratio * s_.min_kbps && may_step) {
    reason += level == 2 ? "; size restored" : "; frame rate restored";
    --level;
    target_ = s_.min_kbps;
  }
  target_ = std::clamp(target_, static_cast<double>(s_.min_kbps), static_cast<double>(s_.max_kbps));
  const int kbps = static_cast<int>(std::lround(target_));
  if (level != st_.level) level_changed_us_ = now_us;
  if (kbps == st_.kbps && level == st_.level) return;
  st_.kbps = kbps;
  st_.level = level;
  st_.reason = std::move(reason);
  st_.changed_us = now_us;
  ++st_.changes;
}

void RateController::onReport(uint64_t now_us, double loss_fraction, std::optional<double> rtt_ms) {
  if (!s_.enabled) return;
  const double p = std::clamp(loss_fraction, 0.0, 1.0);
  const double dt_s = last_report_us_ == 0 ? 1.0 : std::min(static_cast<double>(since(now_us, last_report_us_)) / 1e6, 2.0);
  last_report_us_ = now_us;
  last_timeout_us_ = now_us;
  const std::string loss = "loss " + fmtFixed(100 * p, 1) + " %";
  if (rtt_ms && *rtt_ms >= 0) {
    min_rtt_ms_ = min_rtt_ms_ < 0 ? *rtt_ms : std::min(min_rtt_ms_, *rtt_ms);
    if (*rtt_ms > 2 * min_rtt_ms_ && *rtt_ms > min_rtt_ms_ + s_.rtt_rise_ms) {
      apply(now_us, target_ * s_.rtt_decrease,
            "RTT " + fmtFixed(*rtt_ms, 0) + " ms > 2 x least " + fmtFixed(min_rtt_ms_, 0) + " ms: x" +
                fmtFixed(s_.rtt_decrease, 2));
      return;
    }
  }
  if (p > s_.high_loss) {
    const double f = 1 - 0.5 * p;  // GCC, Eq. (5) of draft-ietf-rmcat-gcc-02 section 6
    apply(now_us, target_ * f, loss + " > " + fmtShort(100 * s_.high_loss) + " %: x" + fmtFixed(f, 2));
  } else if (p < s_.low_loss) {
    const double f = std::pow(s_.increase_per_s, dt_s);
    apply(now_us, target_ * f, loss + " < " + fmtShort(100 * s_.low_loss) + " %: x" + fmtFixed(s_.increase_per_s, 2) + "/s");
  }
  // Between the two: held (the loss a repaired link lives with).
}

void RateController::tick(uint64_t now_us) {
  if (!s_.enabled || last_report_us_ == 0) return;  // before the first report: the start rate
  const auto timeout = static_cast<uint64_t>(s_.report_timeout_s * 1e6);
  if (since(now_us, last_timeout_us_) < timeout) return;
  last_timeout_us_ = now_us;
  apply(now_us, target_ * 0.5,
        "no receiver report for " + fmtFixed(static_cast<double>(since(now_us, last_report_us_)) / 1e6, 1) + " s: x0.5");
}

void RateController::setOperatorRate(uint64_t now_us, int kbps) {
  s_.max_kbps = kbps;
  s_.min_kbps = std::min(s_.min_kbps, kbps);
  target_ = kbps;
  level_changed_us_ = now_us;
  const bool same = st_.kbps == kbps && st_.level == 0;
  st_.kbps = kbps;
  st_.level = 0;
  st_.reason = "operator: " + std::to_string(kbps) + " kbit/s";
  st_.changed_us = now_us;
  if (!same) ++st_.changes;
}

}  // namespace inspect::video
