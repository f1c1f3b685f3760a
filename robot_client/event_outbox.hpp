#pragma once
// Store-and-forward of the robot's events and late acks (docs/store-and-forward.md):
// every Event and every Ack the robot produces on its own (COMPLETED, FAILED)
// gets the next number of the robot's event stream and the robot's UTC time,
// and stays in a bounded queue, in order, and in the journal
// (robot_client/event_journal.hpp), until the server confirms it filed it
// (Envelope.delivered). Entries go out in order through sendNext(): after
// each Hello everything still pending first (marked replayed: the server
// files it at its robot time), then what happens live; the server files each
// (stream, seq) once.
//
// The bound: at most `max_pending` entries. When full, the oldest entry that
// is not a gas alarm is dropped (counted); alarms are never dropped, so the
// queue may hold more than the bound when it holds alarms only.
#include <algorithm>
#include <cstdint>
#include <deque>
#include <memory>
#include <string>

#include "inspect_robot/v1/link.pb.h"
#include "robot_client/event_journal.hpp"

namespace inspect::client {

struct OutboxCounters {
  uint64_t stored = 0;      // entries taken in (this process)
  uint64_t delivered = 0;   // confirmed by the server (this process)
  uint64_t dropped = 0;     // dropped because the queue was full (never alarms)
  uint64_t replayed = 0;    // sent again after a reconnect
  uint64_t loaded = 0;      // pending entries read back from the journal at start
  uint64_t skipped = 0;     // corrupt or torn journal records skipped at start
  uint64_t journal_errors = 0;
};

class EventOutbox {
 public:
  /// `journal_path` "" = memory only (nothing survives a restart). A journal
  /// that cannot be opened is reported by journalError() and the outbox
  /// runs from memory.
  EventOutbox(const std::string& journal_path, std::size_t max_pending, double sync_period_s = 1.0);

  uint64_t stream() const { return stream_; }
  /// Numbers, stamps, queues and journals `env` (an Event or an Ack);
  /// sendNext() sends it.
  void store(v1::Envelope& env, uint64_t wall_time_us);
  /// The server filed everything of our stream up to `seq`.
  void delivered(uint64_t stream, uint64_t up_to_seq);
  /// A connection was accepted: everything pending is to be sent (again).
  void linkUp() {
    ++epoch_;
    cursor_ = 0;
    up_ = true;
  }
  void linkDown() { up_ = false; }
  /// Sends (through `send(v1::Envelope&)`) the pending entries not yet sent on
  /// this connection, oldest first, at most `budget`; returns how many. An
  /// entry sent before, or stored while the link was down, goes marked replayed.
  template <class F>
  std::size_t sendNext(F&& send, std::size_t budget) {
    if (!up_) return 0;
    std::size_t n = 0;
    auto it = std::upper_bound(pending_.begin(), pending_.end(), cursor_,
                               [](uint64_t c, const Pending& p) { return c < p.seq; });
    for (; it != pending_.end() && n < budget; ++it, ++n) {
      const bool replayed = it->sent || it->epoch != epoch_;
      v1::Stored* s = it->env.has_event() ? it->env.mutable_event()->mutable_stored()
                                          : it->env.mutable_ack()->mutable_stored();
      s->set_replayed(replayed);
      counters_.replayed += replayed;
      it->sent = true;
      cursor_ = it->seq;
      send(it->env);
    }
    return n;
  }
  /// Every pending entry, oldest first (tests, logs).
  template <class F>
  void forEachPending(F&& f) const {
    for (const auto& p : pending_) f(p.env);
  }

  std::size_t pending() const { return pending_.size(); }
  std::size_t maxPending() const { return max_pending_; }
  const OutboxCounters& counters() const { return counters_; }
  /// The journal's state for telemetry and logs ("" = fine or no journal).
  std::string journalError() const;
  bool hasJournal() const { return journal_ != nullptr; }
  /// Lines about records skipped when the journal was read back (logged at start).
  const std::vector<std::string>& skippedRecords() const { return skipped_; }

 private:
  struct Pending {
    uint64_t seq;
    bool alarm;
    v1::Envelope env;
    uint64_t epoch = 0;  // the connection it was stored during (0 = link down)
    bool sent = false;   // sent on some connection already
  };
  void dropOne();
  void maybeCompact();

  std::size_t max_pending_;
  std::unique_ptr<EventJournal> journal_;
  std::string open_error_;
  uint64_t stream_ = 0;
  uint64_t next_seq_ = 1;
  uint64_t epoch_ = 0;   // connections so far
  uint64_t cursor_ = 0;  // the last seq sent on this connection
  bool up_ = false;
  std::deque<Pending> pending_;
  OutboxCounters counters_;
  std::vector<std::string> skipped_;
  std::string payload_;  // reused serialization buffer
};

}  // namespace inspect::client
