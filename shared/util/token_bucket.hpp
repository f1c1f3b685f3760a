#pragma once
// A token bucket: `rate` tokens per second, at most `depth` kept. A pure
// function of the times it is given (seconds on any monotonic clock), so it
// is tested without waiting. Used for the robot link's per-robot limits
// (pc_server/link/robot_session.cpp) and the Foxglove bridge's request rate.
#include <algorithm>

namespace inspect::util {

class TokenBucket {
 public:
  TokenBucket(double rate_per_s, double depth) : rate_(rate_per_s), depth_(depth), tokens_(depth) {}

  /// Takes `n` tokens at time `now_s` if there are as many; false (and takes
  /// none) otherwise.
  bool take(double n, double now_s) {
    refill(now_s);
    if (tokens_ < n) return false;
    tokens_ -= n;
    return true;
  }
  double tokens(double now_s) {
    refill(now_s);
    return tokens_;
  }
  double rate() const { return rate_; }

 private:
  void refill(double now_s) {
    if (have_time_ && now_s > last_s_) tokens_ = std::min(depth_, tokens_ + rate_ * (now_s - last_s_));
    if (!have_time_ || now_s > last_s_) last_s_ = now_s;
    have_time_ = true;
  }
  double rate_, depth_, tokens_;
  double last_s_ = 0;
  bool have_time_ = false;
};

}  // namespace inspect::util
