// The catalog's tuning sessions and gains pushes (docs/tuning.md, docs/catalog.md).
#include <algorithm>

#include "shared/catalog/catalog_impl.hpp"

namespace inspect::catalog {

namespace {

using detail::limitOf;
using detail::nullIfEmpty;

// Columns read into a TuningSession by readTuningSession(), in this order.
#define TUNING_COLUMNS                                                                                          \
  "id, session_id, created_unix, COALESCE(robot_id, ''), reference, plant_json, params, algorithm, evals,"     \
  " wall_s, cancelled, initial_cost, best_cost, initial_gains_json, best_gains_json, dir"

// Columns read into a GainsPush by readGainsPush(), in this order.
#define PUSH_COLUMNS "id, robot_id, time_unix, version, gains_json, status, reason, COALESCE(session_id, '')"

bool isPushStatus(std::string_view s) {
  return std::find(std::begin(kPushStatuses), std::end(kPushStatuses), s) != std::end(kPushStatuses);
}

// Costs that are not finite (no evaluation finished) are stored as NULL and read back as NaN.
std::optional<double> finiteOrNull(double v) { return std::isfinite(v) ? std::optional<double>(v) : std::nullopt; }

}  // namespace

void Catalog::addTuningSession(const TuningSession& s) {
  if (s.id.empty()) impl_->failPlain("a tuning session needs an id");
  std::lock_guard lk(impl_->mu);
  {
    auto q = impl_->query("SELECT 1 FROM tuning_sessions WHERE session_id = ?");
    if (q.bind(s.id).step()) impl_->failPlain("tuning session '" + s.id + "' is already recorded");
  }
  impl_->query(
           "INSERT INTO tuning_sessions (session_id, created_time, created_unix, robot_id, reference, plant_json,"
           " params, algorithm, evals, wall_s, cancelled, initial_cost, best_cost, initial_gains_json,"
           " best_gains_json, dir) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)")
      .bind(s.id, s.created, nullIfEmpty(s.robot), s.reference, s.plant_json, s.params, s.algorithm, s.evals,
            s.wall_s, int64_t{s.cancelled ? 1 : 0}, finiteOrNull(s.initial_cost), finiteOrNull(s.best_cost),
            s.initial_gains_json, s.best_gains_json, s.dir)
      .run();
}

std::vector<TuningSession> Catalog::listTuningSessions(int limit) {
  std::lock_guard lk(impl_->mu);
  auto q = impl_->query("SELECT " TUNING_COLUMNS " FROM tuning_sessions ORDER BY created_unix DESC, id DESC LIMIT ?");
  q.bind(limitOf(limit));
  std::vector<TuningSession> out;
  while (q.step()) out.push_back(impl_->readTuningSession(q));
  return out;
}

std::optional<TuningSession> Catalog::tuningSession(const std::string& id) {
  std::lock_guard lk(impl_->mu);
  auto q = impl_->query("SELECT " TUNING_COLUMNS " FROM tuning_sessions WHERE session_id = ?");
  if (!q.bind(id).step()) return std::nullopt;
  return impl_->readTuningSession(q);
}

void Catalog::addGainsPush(const GainsPush& p) {
  if (p.robot.empty()) impl_->failPlain("a gains push needs a robot id");
  if (!isPushStatus(p.status)) impl_->failPlain("unknown gains push status '" + p.status + "' (accepted, rejected)");
  std::lock_guard lk(impl_->mu);
  impl_->query(
           "INSERT INTO gains_pushes (robot_id, time, time_unix, version, gains_json, status, reason, session_id)"
           " VALUES (?, ?, ?, ?, ?, ?, ?, ?)")
      .bind(p.robot, p.time, p.version, p.gains_json, p.status, p.reason, nullIfEmpty(p.session_id))
      .run();
}

std::vector<GainsPush> Catalog::listGainsPushes(const std::string& robot, int limit) {
  std::lock_guard lk(impl_->mu);
  auto q = impl_->query("SELECT " PUSH_COLUMNS
                        " FROM gains_pushes WHERE (CAST(?1 AS TEXT) IS NULL OR robot_id = ?1)"
                        " ORDER BY time_unix DESC, id DESC LIMIT ?2");
  q.bind(nullIfEmpty(robot), limitOf(limit));
  std::vector<GainsPush> out;
  while (q.step()) out.push_back(impl_->readGainsPush(q));
  return out;
}

}  // namespace inspect::catalog
