#pragma once
// A Foxglove client's request rate (docs/foxglove.md "Limits"): a token
// bucket of `per_s` messages a second with 2 s of burst; past it messages are
// refused, and the client is told at most once a second (the other refusals
// are only counted). Pure: times are passed in (seconds, any monotonic clock).
#include "shared/util/token_bucket.hpp"

namespace inspect::server::foxglove {

class RequestRateLimit {
 public:
  enum class Verdict {
    kAllowed,
    kRefusedTell,   // refused: send the client a status saying why
    kRefusedQuiet,  // refused, already told within the last second
  };
  explicit RequestRateLimit(double per_s) : per_s_(per_s), bucket_(per_s, per_s * 2) {}
  Verdict take(double now_s) {
    if (bucket_.take(1, now_s)) return Verdict::kAllowed;
    if (told_ && now_s - last_told_s_ <= 1.0) return Verdict::kRefusedQuiet;
    told_ = true;
    last_told_s_ = now_s;
    return Verdict::kRefusedTell;
  }
  double perSecond() const { return per_s_; }

 private:
  double per_s_;
  util::TokenBucket bucket_;
  bool told_ = false;
  double last_told_s_ = 0.0;
};

}  // namespace inspect::server::foxglove
