#pragma once
// Inside the run catalog (not for its users): Catalog::Impl, a statement's
// parameters and rows (Query), transactions (Tx), and what the files of
// catalog*.cpp share. One home: catalog.cpp (runs, events, alarms, files),
// catalog_sessions.cpp (tuning sessions, gains pushes), catalog_fleet.cpp
// (servers, presence).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "shared/catalog/catalog.hpp"
#include "shared/catalog/sql_backend.hpp"
#include "shared/catalog/time_text.hpp"

namespace inspect::catalog {

namespace detail {

// "No limit" for LIMIT ?: both engines take the largest 64-bit integer.
// A parameter that may be NULL is CAST where it is first used (`CAST(?1 AS
// TEXT) IS NULL OR ...`): PostgreSQL must know its type, SQLite reads the
// same CAST (DOUBLE PRECISION has REAL affinity there).
inline constexpr int64_t kNoLimit = std::numeric_limits<int64_t>::max();

inline int64_t limitOf(int limit) { return limit > 0 ? limit : kNoLimit; }

// The schema version that adds server_id to runs, events and alarms.
inline constexpr std::size_t kServerIdsVersion = 5;

inline bool allDigits(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// Columns read into a RunInfo by Impl::readRun(), in this order.
#define RUN_COLUMNS                                                                                                \
  "id, run_id, robot_id, name, route, gains_json, software_version, dir, start_unix, end_unix, COALESCE(outcome, ''),"  \
  " server_id"

inline std::optional<std::string_view> nullIfEmpty(const std::string& s) {
  return s.empty() ? std::nullopt : std::optional<std::string_view>(s);
}

}  // namespace detail

struct Catalog::Impl {
  std::unique_ptr<SqlBackend> db;
  std::recursive_mutex mu;
  int tx_depth = 0;  // Tx objects alive: only the outermost begins and commits
  std::string server_id;
  bool fleet = true;  // the schema has version 5's server columns (false only when opened older, in tests)

  [[noreturn]] void failPlain(const std::string& what) const {
    failCatalog(db->where(), what);
  }

  // A statement, its parameters bound in order, then its rows read.
  class Query {
   public:
    Query(Impl& impl, std::string_view sql) : impl_(impl), sql_(sql) {}
    Query(const Query&) = delete;
    Query& operator=(const Query&) = delete;

    // Binds the arguments to ?1, ?2, ... in order; a Time takes two: ISO text, unix seconds.
    template <class... A>
    Query& bind(const A&... a) {
      (bindOne(a), ...);
      return *this;
    }
    // True: a row is ready; false: done. Runs the statement at the first call.
    bool step() {
      if (!ran_) {
        result_ = impl_.db->run(sql_, params_);
        ran_ = true;
        row_ = 0;
      } else {
        ++row_;
      }
      return row_ < result_.rows.size();
    }
    // Runs the statement; the rows it changed.
    int64_t run() {
      step();
      return result_.changed;
    }

    // Reads columns 0, 1, ... of the current row into the arguments in order
    // (a Time from unix seconds; an optional stays empty for NULL).
    template <class... A>
    void read(A&... a) const {
      std::size_t c = 0;
      (readOne(c++, a), ...);
    }
    template <class T>
    T column(std::size_t c) const {
      T v{};
      readOne(c, v);
      return v;
    }

   private:
    const SqlValue& at(std::size_t c) const { return result_.rows[row_][c]; }
    double number(std::size_t c) const {
      const SqlValue& v = at(c);
      if (const auto* d = std::get_if<double>(&v)) return *d;
      if (const auto* n = std::get_if<int64_t>(&v)) return static_cast<double>(*n);
      if (const auto* t = std::get_if<std::string>(&v)) return std::strtod(t->c_str(), nullptr);
      return 0.0;
    }
    void readOne(std::size_t c, std::string& v) const {
      const SqlValue& x = at(c);
      if (const auto* t = std::get_if<std::string>(&x)) v = *t;
      else if (const auto* n = std::get_if<int64_t>(&x)) v = std::to_string(*n);
      else v.clear();
    }
    void readOne(std::size_t c, double& v) const { v = number(c); }
    void readOne(std::size_t c, int64_t& v) const {
      const SqlValue& x = at(c);
      const auto* n = std::get_if<int64_t>(&x);
      v = n ? *n : static_cast<int64_t>(number(c));
    }
    void readOne(std::size_t c, Time& v) const { v = fromUnix(number(c)); }
    template <class T>
    void readOne(std::size_t c, std::optional<T>& v) const {
      if (std::holds_alternative<std::monostate>(at(c))) {
        v.reset();
      } else {
        readOne(c, v.emplace());
      }
    }

    void bindOne(std::string_view v) { params_.emplace_back(std::string(v)); }
    void bindOne(const std::string& v) { params_.emplace_back(v); }
    void bindOne(const char* v) { params_.emplace_back(std::string(v)); }
    void bindOne(double v) { params_.emplace_back(v); }
    void bindOne(int64_t v) { params_.emplace_back(v); }
    void bindOne(int v) { params_.emplace_back(static_cast<int64_t>(v)); }
    void bindOne(Time t) {
      bindOne(formatIsoUtc(t));
      bindOne(unixSeconds(t));
    }
    template <class T>
    void bindOne(const std::optional<T>& v) {
      static_assert(!std::is_same_v<T, Time>, "an empty optional<Time> would bind one NULL for two parameters");
      if (v) {
        bindOne(*v);
      } else {
        params_.emplace_back(std::monostate{});
      }
    }

    Impl& impl_;
    std::string_view sql_;
    std::vector<SqlValue> params_;
    SqlResult result_;
    std::size_t row_ = 0;
    bool ran_ = false;
  };

  // `sql` must outlive the Catalog (a literal): it keys the prepared statements.
  Query query(std::string_view sql) { return Query(*this, sql); }

  // A transaction rolled back unless committed. Nested in another (a write
  // of applySpooled), it is part of the outer one, which begins and commits.
  class Tx {
   public:
    explicit Tx(Impl& impl, bool write = true) : impl_(impl), outer_(impl.tx_depth == 0) {
      if (outer_) impl_.db->begin(write);
      ++impl_.tx_depth;
    }
    Tx(const Tx&) = delete;
    Tx& operator=(const Tx&) = delete;
    ~Tx() {
      --impl_.tx_depth;
      if (outer_ && !done_) impl_.db->rollback();
    }
    void commit() {
      if (outer_) impl_.db->commit();
      done_ = true;
    }

   private:
    Impl& impl_;
    bool outer_;
    bool done_ = false;
  };

  RunInfo readRun(const Query& q) const {
    RunInfo r;
    q.read(r.rowid, r.id, r.robot, r.name, r.route, r.gains_json, r.software_version, r.dir, r.start, r.end, r.outcome,
           r.server);
    return r;
  }

  std::optional<RunInfo> findRun(const std::string& run_id) {
    auto q = detail::allDigits(run_id) ? query("SELECT " RUN_COLUMNS " FROM runs WHERE id = ?")
                               : query("SELECT " RUN_COLUMNS " FROM runs WHERE run_id = ?");
    if (detail::allDigits(run_id)) {
      q.bind(static_cast<int64_t>(std::stoll(run_id)));
    } else {
      q.bind(run_id);
    }
    if (!q.step()) return std::nullopt;
    return readRun(q);
  }

  TuningSession readTuningSession(const Query& q) const {
    TuningSession s;
    int64_t cancelled = 0;
    std::optional<double> initial_cost, best_cost;
    q.read(s.rowid, s.id, s.created, s.robot, s.reference, s.plant_json, s.params, s.algorithm, s.evals, s.wall_s,
           cancelled, initial_cost, best_cost, s.initial_gains_json, s.best_gains_json, s.dir);
    s.cancelled = cancelled != 0;
    s.initial_cost = initial_cost.value_or(std::nan(""));
    s.best_cost = best_cost.value_or(std::nan(""));
    return s;
  }

  GainsPush readGainsPush(const Query& q) const {
    GainsPush p;
    q.read(p.rowid, p.robot, p.time, p.version, p.gains_json, p.status, p.reason, p.session_id);
    return p;
  }

  std::optional<Summary> readSummary(const std::string& run_id) {
    auto q = query(
        "SELECT duration_s, distance_m, min_person_m, track_max_pos_err_m, track_rms_pos_err_m,"
        " track_max_angle_err_rad, video_frames_received, video_frames_decoded, video_packets_lost"
        " FROM run_summary WHERE run_id = ?");
    q.bind(run_id);
    if (!q.step()) return std::nullopt;
    Summary s;
    q.read(s.duration_s, s.distance_m, s.min_person_m, s.track_max_pos_err_m, s.track_rms_pos_err_m,
           s.track_max_angle_err_rad, s.video_frames_received, s.video_frames_decoded, s.video_packets_lost);
    auto g = query("SELECT channel, unit, max, mean FROM run_gas WHERE run_id = ? ORDER BY channel");
    g.bind(run_id);
    while (g.step()) {
      auto& gas = s.gas.emplace_back();
      g.read(gas.channel, gas.unit, gas.max, gas.mean);
    }
    return s;
  }
};

}  // namespace inspect::catalog
