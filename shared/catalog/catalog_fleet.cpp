// The catalog of a fleet's servers: each server's id on what it writes, the
// servers' rows and where each robot is (docs/catalog.md, version 5).
#include "shared/catalog/catalog_impl.hpp"

namespace inspect::catalog {

void Catalog::setServerId(const std::string& id) {
  std::lock_guard lk(impl_->mu);
  impl_->server_id = id;
}

const std::string& Catalog::serverId() const { return impl_->server_id; }

void Catalog::upsertServer(const ServerInfo& s) {
  if (s.id.empty()) impl_->failPlain("a server needs an id");
  std::lock_guard lk(impl_->mu);
  impl_->query(
           "INSERT INTO servers (id, attach, runs_root, software_version, started_time, started_unix, seen_time,"
           " seen_unix) VALUES (?, ?, ?, ?, ?, ?, ?, ?) ON CONFLICT (id) DO UPDATE SET attach = excluded.attach,"
           " runs_root = excluded.runs_root, software_version = excluded.software_version,"
           " started_time = excluded.started_time, started_unix = excluded.started_unix,"
           " seen_time = excluded.seen_time, seen_unix = excluded.seen_unix")
      .bind(s.id, s.attach, s.runs_root, s.software_version, s.started, s.seen)
      .run();
}

std::vector<ServerInfo> Catalog::listServers() {
  std::lock_guard lk(impl_->mu);
  auto q = impl_->query(
      "SELECT id, attach, runs_root, software_version, started_unix, seen_unix FROM servers"
      " ORDER BY seen_unix DESC, id");
  std::vector<ServerInfo> out;
  while (q.step()) {
    auto& s = out.emplace_back();
    q.read(s.id, s.attach, s.runs_root, s.software_version, s.started, s.seen);
  }
  return out;
}

void Catalog::setPresence(const RobotPresence& p) {
  if (p.robot.empty() || p.server.empty()) impl_->failPlain("a presence needs a robot and a server id");
  std::lock_guard lk(impl_->mu);
  impl_->query(
           "INSERT INTO robot_presence (robot_id, server_id, online, mode, x_m, y_m, seen_time, seen_unix)"
           " VALUES (?, ?, ?, ?, ?, ?, ?, ?) ON CONFLICT (robot_id) DO UPDATE SET server_id = excluded.server_id,"
           " online = excluded.online, mode = excluded.mode, x_m = excluded.x_m, y_m = excluded.y_m,"
           " seen_time = excluded.seen_time, seen_unix = excluded.seen_unix")
      .bind(p.robot, p.server, int64_t{p.online ? 1 : 0}, p.mode, p.x_m, p.y_m, p.seen)
      .run();
}

std::vector<RobotPresence> Catalog::listPresence() {
  std::lock_guard lk(impl_->mu);
  auto q = impl_->query(
      "SELECT robot_id, server_id, online, mode, x_m, y_m, seen_unix FROM robot_presence ORDER BY robot_id");
  std::vector<RobotPresence> out;
  while (q.step()) {
    auto& p = out.emplace_back();
    int64_t online = 0;
    q.read(p.robot, p.server, online, p.mode, p.x_m, p.y_m, p.seen);
    p.online = online != 0;
  }
  return out;
}

int64_t Catalog::applySpooled(const std::string& spool_id, std::span<const int64_t> seqs,
                              const std::function<void(std::size_t)>& write) {
  if (seqs.empty()) return 0;
  std::lock_guard lk(impl_->mu);
  Impl::Tx tx(*impl_);
  const int64_t applied = spoolApplied(spool_id);
  int64_t ran = 0;
  for (std::size_t i = 0; i < seqs.size(); ++i) {
    if (seqs[i] <= applied) continue;  // written before (the spool did not hear the commit)
    write(i);
    ++ran;
  }
  const int64_t last = seqs.back();
  if (last > applied)
    impl_->query("INSERT INTO spool_applied (spool_id, server_id, seq, time, time_unix) VALUES (?, ?, ?, ?, ?)"
                 " ON CONFLICT (spool_id) DO UPDATE SET seq = excluded.seq, time = excluded.time,"
                 " time_unix = excluded.time_unix")
        .bind(spool_id, impl_->server_id, last, std::chrono::system_clock::now())
        .run();
  tx.commit();
  return ran;
}

int64_t Catalog::spoolApplied(const std::string& spool_id) {
  std::lock_guard lk(impl_->mu);
  auto q = impl_->query("SELECT seq FROM spool_applied WHERE spool_id = ?");
  return q.bind(spool_id).step() ? q.column<int64_t>(0) : 0;
}

}  // namespace inspect::catalog
