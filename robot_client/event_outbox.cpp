#include "robot_client/event_outbox.hpp"

#include <stdexcept>

namespace inspect::client {

namespace {
// Compaction: once everything is delivered and the file passed this, or
// whenever it passed the hard bound (then with what is pending).
constexpr uint64_t kCompactWhenEmptyBytes = 64 * 1024;
constexpr uint64_t kCompactAlwaysBytes = 8 * 1024 * 1024;

bool isAlarm(const v1::Envelope& env) {
  return env.has_event() && (env.event().kind() == v1::Event::ALARM_RAISED ||
                             env.event().kind() == v1::Event::ALARM_CLEARED || env.event().has_gas_alarm());
}
}  // namespace

EventOutbox::EventOutbox(const std::string& journal_path, std::size_t max_pending, double sync_period_s)
    : max_pending_(max_pending) {
  if (!journal_path.empty()) {
    try {
      journal_ = std::make_unique<EventJournal>(journal_path, sync_period_s);
    } catch (const std::exception& e) {
      open_error_ = e.what();
      ++counters_.journal_errors;
    }
  }
  if (!journal_) {
    // Memory only: a stream of its own for this process.
    stream_ = EventJournal::newStreamId();
    return;
  }
  auto& l = journal_->loaded();
  stream_ = l.stream;
  next_seq_ = l.next_seq;
  skipped_ = l.skipped;
  counters_.skipped = l.skipped.size();
  for (auto& e : l.pending) {
    Pending p{e.seq, false, {}, 0, false};
    if (!p.env.ParseFromString(e.payload) || (!p.env.has_event() && !p.env.has_ack())) {
      skipped_.push_back("entry seq " + std::to_string(e.seq) + ": its checksum holds but it is no Event or Ack; skipped");
      ++counters_.skipped;
      continue;
    }
    // Entries re-numbered under a new stream (their header was lost) carry it.
    if (p.env.has_event()) p.env.mutable_event()->mutable_stored()->set_seq(e.seq);
    if (p.env.has_ack()) p.env.mutable_ack()->mutable_stored()->set_seq(e.seq);
    p.alarm = isAlarm(p.env);
    pending_.push_back(std::move(p));
    ++counters_.loaded;
  }
  l.pending.clear();
}

void EventOutbox::store(v1::Envelope& env, uint64_t wall_time_us) {
  v1::Stored* s = env.has_event() ? env.mutable_event()->mutable_stored()
                  : env.has_ack() ? env.mutable_ack()->mutable_stored()
                                  : nullptr;
  if (!s) throw std::logic_error("EventOutbox::store: only Events and Acks are stored");
  s->set_seq(next_seq_++);
  s->set_wall_time_us(wall_time_us);
  s->set_replayed(false);
  if (pending_.size() >= max_pending_) dropOne();
  pending_.push_back({s->seq(), isAlarm(env), env, up_ ? epoch_ : 0, false});
  ++counters_.stored;
  if (journal_) {
    payload_.clear();
    env.SerializeToString(&payload_);
    if (!journal_->append(s->seq(), payload_)) ++counters_.journal_errors;
  }
}

void EventOutbox::dropOne() {
  for (auto it = pending_.begin(); it != pending_.end(); ++it) {
    if (it->alarm) continue;
    if (journal_ && !journal_->markDropped(it->seq)) ++counters_.journal_errors;
    pending_.erase(it);
    ++counters_.dropped;
    return;
  }
  // Alarms only: keep them all (the bound yields to the alarms).
}

void EventOutbox::delivered(uint64_t stream, uint64_t up_to_seq) {
  if (stream != stream_) return;  // another (older) stream's confirmation
  bool any = false;
  while (!pending_.empty() && pending_.front().seq <= up_to_seq) {
    pending_.pop_front();
    ++counters_.delivered;
    any = true;
  }
  if (!any || !journal_) return;
  if (!journal_->markDelivered(up_to_seq)) ++counters_.journal_errors;
  maybeCompact();
}

void EventOutbox::maybeCompact() {
  const uint64_t bytes = journal_->bytes();
  if (!(pending_.empty() && bytes > kCompactWhenEmptyBytes) && bytes <= kCompactAlwaysBytes) return;
  std::vector<EventJournal::Entry> keep;
  keep.reserve(pending_.size());
  for (const auto& p : pending_) keep.push_back({p.seq, p.env.SerializeAsString()});
  if (!journal_->compact(keep, next_seq_)) ++counters_.journal_errors;
}

std::string EventOutbox::journalError() const {
  if (!open_error_.empty()) return open_error_;
  return journal_ ? journal_->error() : std::string();
}

}  // namespace inspect::client
