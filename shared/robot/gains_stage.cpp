#include "shared/robot/gains_stage.hpp"

#include <cstdio>

#include "shared/fuzzy/fis_reader.hpp"
#include "shared/net/gains_proto.hpp"

namespace inspect::robot {

GainsStage::GainsStage(const config::ControlConfig& control, std::shared_ptr<control::FuzzyGainScheduler> scheduler)
    : use_lookup_(control.use_lookup), scheduler_(std::move(scheduler)) {
  gains_.fuzzy = control.tracker.fuzzy;
  gains_.aux = control.tracker.aux;
}

v1::Ack GainsStage::stage(const v1::Command& cmd, bool moving, v1::Mode mode) {
  const auto& u = cmd.gains();
  v1::Ack ack = ackOf(cmd.id(), v1::Ack::REJECTED);
  ack.set_gains_version(version_);  // the version in force now
  if (!u.has_gains()) {
    ack.set_reason("gains update without gains");
    return ack;
  }
  Pending p;
  p.gains = net::fromProto(u.gains());
  if (const std::string why = control::validateGains(p.gains); !why.empty()) {
    ack.set_reason("gains refused: " + why);
    return ack;
  }
  if (!u.fis().empty()) {
    if (u.fis().size() > 64 * 1024) {
      ack.set_reason("fuzzy system refused: larger than 64 KiB");
      return ack;
    }
    if (moving) {
      ack.set_reason("fuzzy system refused: the robot is moving (" + std::string(v1::Mode_Name(mode)) +
                     "); push it while it stands still");
      return ack;
    }
    try {
      const fuzzy::Fis fis = fuzzy::parseFis(u.fis(), "pushed fuzzy system");
      p.scheduler = std::make_shared<control::FuzzyGainScheduler>(fis, use_lookup_);
      p.fis_name = fis.name;
    } catch (const std::exception& e) {
      ack.set_reason(std::string("fuzzy system refused: ") + e.what());
      return ack;
    }
  }
  p.source = u.source();
  p.version = (pending_ ? pending_->version : version_) + 1;
  // A second update before the next tick replaces the first (keeping a new
  // fuzzy system the first one brought, unless this one brings its own).
  if (pending_ && !p.scheduler && pending_->scheduler) {
    p.scheduler = pending_->scheduler;
    p.fis_name = pending_->fis_name;
  }
  pending_ = std::move(p);
  ack.set_status(v1::Ack::ACCEPTED);
  ack.set_gains_version(pending_->version);
  ack.set_reason("in force from the next control tick");
  return ack;
}

std::optional<GainsStage::Applied> GainsStage::applyPending(bool tracking) {
  if (!pending_) return std::nullopt;
  Pending p = std::move(*pending_);
  pending_.reset();
  gains_ = p.gains;
  version_ = p.version;
  if (p.scheduler) {
    scheduler_ = p.scheduler;
    fis_name_ = p.fis_name;
  }
  Applied out;
  CoreEvent& e = out.event;
  e.kind = v1::Event::GAINS_APPLIED;
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "gains v%u in force%s: kp' %.4g ki' %.4g kd' %.4g ke %.4g kec %.4g k1 %.4g k2 %.4g k3 %.4g a1 %.4g "
                "a2 %.4g a3 %.4g",
                version_, tracking ? " (also on the path being tracked)" : "", gains_.fuzzy.base.kp,
                gains_.fuzzy.base.ki, gains_.fuzzy.base.kd, gains_.fuzzy.ke, gains_.fuzzy.kec, gains_.fuzzy.k1,
                gains_.fuzzy.k2, gains_.fuzzy.k3, gains_.aux.a1, gains_.aux.a2, gains_.aux.a3);
  e.text = buf;
  if (!p.source.empty()) e.text += " from " + p.source;
  if (p.scheduler) e.text += ", fuzzy system '" + fis_name_ + "'";
  v1::Gains g;
  net::toProto(gains_, g);
  e.gains = g;
  e.gains_version = version_;
  out.new_scheduler = std::move(p.scheduler);
  return out;
}

}  // namespace inspect::robot
